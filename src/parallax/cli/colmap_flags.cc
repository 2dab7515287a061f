#include "parallax/cli/colmap_flags.h"

#include <algorithm>
#include <cctype>
#include <map>

#include "parallax/util/check.h"

namespace parallax::cli {

namespace {

// Options of COLMAP's option manager that every subcommand accepts.
const std::vector<std::string>& CommonIgnoredOptions() {
  static const std::vector<std::string> names = {
      "project_path", "log_to_stderr", "log_level", "default_random_seed",
      "random_seed",  "log_target",    "log_path",  "log_severity",
      "log_color"};
  return names;
}

}  // namespace

bool ParseColmapBool(const std::string& option, const std::string& value) {
  std::string lower = value;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (lower == "1" || lower == "true") return true;
  if (lower == "0" || lower == "false") return false;
  throw InputError("option '--" + option + "' takes 0, 1, true or false, not '" + value + "'");
}

ColmapTranslation TranslateColmapArgs(const std::string& subcommand,
                                      const std::vector<std::string>& args,
                                      const std::vector<ColmapOption>& table) {
  ColmapTranslation translation;
  // The name each value option was given under: one given twice, or under both its 3.x and
  // 4.x names, is refused here (as COLMAP refuses it) rather than by the Parallax command.
  std::map<const ColmapOption*, std::string> value_given_as;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg == "-h" || arg == "--help") {
      translation.help = true;
      continue;
    }
    if (arg.rfind("--", 0) != 0 || arg.size() == 2) {
      throw InputError("colmap " + subcommand + ": unexpected argument '" + arg + "'");
    }
    std::string name = arg.substr(2), value;
    bool has_value = false;
    if (const size_t equals = name.find('='); equals != std::string::npos) {
      value = name.substr(equals + 1);
      name = name.substr(0, equals);
      has_value = true;
    } else if (i + 1 < args.size() && args[i + 1].rfind("--", 0) != 0) {
      value = args[++i];
      has_value = true;
    }
    const auto option = std::find_if(table.begin(), table.end(), [&name](const ColmapOption& o) {
      return std::find(o.names.begin(), o.names.end(), name) != o.names.end();
    });
    if (option == table.end()) {
      const auto& common = CommonIgnoredOptions();
      if (std::find(common.begin(), common.end(), name) != common.end()) {
        translation.warnings.push_back("--" + name + " has no meaning for Parallax; ignored");
        continue;
      }
      throw InputError("colmap " + subcommand + ": unrecognised option '--" + name + "'");
    }
    // COLMAP's booleans may stand alone (`--flag` for true).
    const bool is_bool = option->kind == ColmapOption::Kind::kFlagIfOn ||
                         option->kind == ColmapOption::Kind::kFlagIfOff;
    if (!has_value && !is_bool && option->kind != ColmapOption::Kind::kIgnored) {
      throw InputError("colmap " + subcommand + ": option '--" + name + "' needs a value");
    }
    switch (option->kind) {
      case ColmapOption::Kind::kValue:
        if (const auto [given, first] = value_given_as.emplace(&*option, name); !first) {
          throw InputError("colmap " + subcommand + ": --" + given->second + " and --" + name +
                           " set the same option; give it once");
        }
        translation.parallax_args.push_back(option->parallax_flag);
        translation.parallax_args.push_back(value);
        break;
      case ColmapOption::Kind::kFlagIfOn:
      case ColmapOption::Kind::kFlagIfOff: {
        const bool on = has_value ? ParseColmapBool(name, value) : true;
        if (on == (option->kind == ColmapOption::Kind::kFlagIfOn)) {
          translation.parallax_args.push_back(option->parallax_flag);
        }
        break;
      }
      case ColmapOption::Kind::kIgnored:
        translation.warnings.push_back("--" + name + " " + option->why_ignored + "; ignored");
        break;
      case ColmapOption::Kind::kCustom:
        option->apply(value, &translation.parallax_args);
        break;
    }
  }
  return translation;
}

}  // namespace parallax::cli
