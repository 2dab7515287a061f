#include "parallax/cli/process_setup.h"

#include <csignal>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace parallax::cli {

namespace {

// Keeps freed buffers of up to tens of megabytes in the process. Every bundle adjustment
// allocates its Jacobians and reduced system afresh (7 MB on templeRing's 44,000
// observations) and frees them; glibc's default gives that memory back to the kernel, and
// the next adjustment faults it in again page by page (docs/performance.md,
// "Freed bundle-adjustment buffers kept in the process").
void KeepFreedLargeBuffers() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, 32 << 20);  // glibc's own upper bound for its adaptive threshold.
  mallopt(M_TRIM_THRESHOLD, 128 << 20);
#endif
}

}  // namespace

void PrepareProcess() {
  // A write past a file-size limit (ulimit -f) then fails with EFBIG and a one-line error
  // naming the file, instead of SIGXFSZ ending the process with a core dump.
  std::signal(SIGXFSZ, SIG_IGN);
  KeepFreedLargeBuffers();
}

}  // namespace parallax::cli
