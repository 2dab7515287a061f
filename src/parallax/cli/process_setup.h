#pragma once

namespace parallax::cli {

// What both executables (parallax, colmap) set up before any work: a write past a file-size
// limit fails with a one-line error instead of SIGXFSZ's core dump, and large freed buffers
// stay in the process (docs/performance.md, "Freed bundle-adjustment buffers kept in the
// process").
void PrepareProcess();

}  // namespace parallax::cli
