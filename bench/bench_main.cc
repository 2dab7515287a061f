// The main of the micro-benchmarks that need nothing before they run but a seeded generator,
// so that every run measures the same synthetic inputs.
#include <benchmark/benchmark.h>

#include "parallax/math/random.h"

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  parallax::SetPRNGSeed(0);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
