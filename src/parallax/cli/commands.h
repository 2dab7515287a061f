#pragma once

// One entry point per subcommand. Each parses its own arguments (argv[0] is the subcommand
// name) with CLI11 and returns the process exit code.
namespace parallax::cli {

int RunVersion(int argc, char** argv);
int RunDemo(int argc, char** argv);
int RunCalibrate(int argc, char** argv);
int RunFeatures(int argc, char** argv);
int RunMatch(int argc, char** argv);
int RunMapper(int argc, char** argv);
int RunReconstruct(int argc, char** argv);
int RunSynth(int argc, char** argv);
int RunEvaluate(int argc, char** argv);
int RunReport(int argc, char** argv);
int RunUndistort(int argc, char** argv);
int RunExport(int argc, char** argv);
int RunModel(int argc, char** argv);

}  // namespace parallax::cli
