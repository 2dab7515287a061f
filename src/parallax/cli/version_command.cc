#include <iostream>

#include "parallax/cli/cli_common.h"
#include "parallax/cli/commands.h"
#include "parallax/distributed/process_group.h"

namespace parallax::cli {

int RunVersion(int argc, char** argv) {
  CLI::App app("Print the version of Parallax", "parallax version");
  VerbosityFlags flags;
  return RunCommand(app, argc, argv, flags, [] {
    std::cout << "parallax 0.1.0\n"
              << "distributed runs (mpirun, srun): "
              << (BuiltWithMpi() ? "yes, MPI" : "no, built without MPI") << std::endl;
    return 0;
  });
}

}  // namespace parallax::cli
