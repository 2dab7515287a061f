#pragma once

// COLMAP's command-line conventions, for the `colmap` drop-in: its options are
// `--name value` or `--name=value`, `--Section.option` for the sections of its option manager,
// and booleans written 0/1/true/false. A table per subcommand maps each COLMAP option (under
// the names both generations give it: 3.x `SiftExtraction.*`/`SiftMatching.*`, 4.x
// `FeatureExtraction.*`/`FeatureMatching.*`) to the Parallax flag that sets the same option.

#include <functional>
#include <string>
#include <vector>

namespace parallax::cli {

// What one COLMAP option becomes.
struct ColmapOption {
  enum class Kind {
    kValue,      // `--parallax_flag VALUE`.
    kFlagIfOn,   // A boolean: `--parallax_flag` when true, nothing when false.
    kFlagIfOff,  // A boolean: `--parallax_flag` when false, nothing when true.
    kIgnored,    // Accepted with one warning: it has no meaning for Parallax.
    kCustom,     // `apply(value, &parallax_args)`.
  };
  std::vector<std::string> names;  // Without the leading dashes; the first is the 4.x name.
  Kind kind = Kind::kValue;
  std::string parallax_flag;
  std::string why_ignored;  // kIgnored: said in the warning.
  std::function<void(const std::string& value, std::vector<std::string>* parallax_args)> apply;
};

struct ColmapTranslation {
  std::vector<std::string> parallax_args;  // After the Parallax subcommand's name.
  std::vector<std::string> warnings;       // One line per ignored option.
  bool help = false;                       // -h / --help was given.
};

// Reads COLMAP `args` (after the subcommand) against `table`. An option the table does not
// name, a missing value or a boolean that is not 0/1/true/false throws InputError naming it,
// as COLMAP fails; options COLMAP's every subcommand takes (logging, --project_path) are
// ignored with a warning.
ColmapTranslation TranslateColmapArgs(const std::string& subcommand,
                                      const std::vector<std::string>& args,
                                      const std::vector<ColmapOption>& table);

// COLMAP's boolean spellings; throws InputError naming `option` otherwise.
bool ParseColmapBool(const std::string& option, const std::string& value);

}  // namespace parallax::cli
