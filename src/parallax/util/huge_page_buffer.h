#pragma once

#include <cstddef>

namespace parallax {

// A block of memory for large working buffers that are reused between calls (scale
// spaces of a few tens of megabytes): aligned to 2 MiB and, on Linux, advised to be backed
// by transparent huge pages where the kernel allows them only on request (the "madvise"
// setting, Debian's default). With 4 KiB pages, first touching such buffers cost each
// extraction thread a page fault per 4 KiB (docs/performance.md, "Scale space in huge pages"), and
// the vertical blur's taps, one image row apart, a TLB entry each.
class HugePageBuffer {
 public:
  HugePageBuffer() = default;
  ~HugePageBuffer();
  HugePageBuffer(const HugePageBuffer&) = delete;
  HugePageBuffer& operator=(const HugePageBuffer&) = delete;

  // At least `bytes` bytes, 64-byte aligned; the contents are kept only while the buffer
  // does not grow (a larger request frees the old block and allocates a new one).
  void* Reserve(size_t bytes);
  size_t Capacity() const { return capacity_; }

 private:
  void* data_ = nullptr;
  size_t capacity_ = 0;
};

}  // namespace parallax
