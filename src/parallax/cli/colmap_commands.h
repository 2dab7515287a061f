#pragma once

// The `colmap` drop-in's subcommands (colmap_commands.cc); each takes COLMAP's options of
// either generation (argv[0] is the subcommand's name) and returns the process exit code.
namespace parallax::cli {

int RunColmapFeatureExtractor(int argc, char** argv);
int RunColmapExhaustiveMatcher(int argc, char** argv);
int RunColmapSequentialMatcher(int argc, char** argv);
int RunColmapVocabTreeMatcher(int argc, char** argv);
int RunColmapSpatialMatcher(int argc, char** argv);
int RunColmapMatchesImporter(int argc, char** argv);
int RunColmapMapper(int argc, char** argv);
int RunColmapHierarchicalMapper(int argc, char** argv);
int RunColmapModelAnalyzer(int argc, char** argv);
int RunColmapImageUndistorter(int argc, char** argv);
int RunColmapModelAligner(int argc, char** argv);
int RunColmapModelConverter(int argc, char** argv);
int RunColmapPointTriangulator(int argc, char** argv);
int RunColmapImageRegistrator(int argc, char** argv);
int RunColmapBundleAdjuster(int argc, char** argv);
int RunColmapModelMerger(int argc, char** argv);
int RunColmapDatabaseCreator(int argc, char** argv);
int RunColmapAutomaticReconstructor(int argc, char** argv);

}  // namespace parallax::cli
