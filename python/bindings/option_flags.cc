#include "option_flags.h"

#include <algorithm>
#include <sstream>
#include <vector>

namespace py = pybind11;

namespace parallax::python {
namespace {

std::string FlagOfKeyword(const std::string& keyword) {
  std::string flag = "--" + keyword;
  std::replace(flag.begin(), flag.end(), '_', '-');
  return flag;
}

// The keyword of an option: its first long name with '_' for '-' ("!--no-exif" -> no_exif).
std::string KeywordOfOption(const CLI::Option& option) {
  std::string name = option.get_lnames().empty() ? option.get_name() : option.get_lnames().front();
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

bool IsFlag(const CLI::Option& option) { return option.get_expected_max() == 0; }

// Python's name for the type a flag's value converts to.
std::string PythonType(const CLI::Option& option) {
  if (IsFlag(option)) return "bool";
  const std::string type = option.get_type_name();
  if (type.find("FLOAT") != std::string::npos) return "float";
  if (type.find("INT") != std::string::npos) return "int";
  return "str";
}

// The command-line text of one value: lists joined by commas, paths as paths.
std::string ValueText(const py::handle& value) {
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
    std::string text;
    for (const py::handle item : value) {
      if (!text.empty()) text += ",";
      text += ValueText(item);
    }
    return text;
  }
  if (py::isinstance<py::float_>(value)) return py::repr(value).cast<std::string>();
  if (py::hasattr(value, "__fspath__")) {
    return py::module_::import("os").attr("fspath")(value).cast<std::string>();
  }
  return py::str(value).cast<std::string>();
}

std::vector<const CLI::Option*> KeywordOptions(const CLI::App& app) {
  std::vector<const CLI::Option*> options;
  for (const CLI::Option* option : app.get_options()) {
    if (option == app.get_help_ptr() || option->get_lnames().empty()) continue;
    options.push_back(option);
  }
  return options;
}

}  // namespace

void ParseKeywordOptions(const std::string& function_name, const py::kwargs& options,
                         CLI::App& app) {
  std::vector<std::string> args;
  for (const auto& [key, value] : options) {
    const std::string keyword = key.cast<std::string>();
    const std::string flag = FlagOfKeyword(keyword);
    const CLI::Option* option = app.get_option_no_throw(flag);
    if (py::isinstance<py::bool_>(value)) {
      const bool on = value.cast<bool>();
      const CLI::Option* negation = app.get_option_no_throw(FlagOfKeyword("no_" + keyword));
      if (option != nullptr && IsFlag(*option) && on) {
        args.push_back(flag);
        continue;
      }
      if (!on && (negation != nullptr || (option != nullptr && IsFlag(*option)))) {
        // `exif=False` is --no-exif; a flag that is off by default stays off.
        if (negation != nullptr) args.push_back(FlagOfKeyword("no_" + keyword));
        continue;
      }
    }
    if (option == nullptr) {
      throw py::type_error(function_name + "() got an unexpected keyword argument '" + keyword +
                           "'");
    }
    if (IsFlag(*option)) {
      throw py::type_error(function_name + "(): " + keyword + " takes True or False");
    }
    args.push_back(flag);
    args.push_back(ValueText(value));
  }
  std::reverse(args.begin(), args.end());  // CLI11 takes the arguments last first.
  try {
    app.parse(args);
  } catch (const CLI::ParseError& error) {
    throw py::value_error(function_name + "(): " + error.what());
  }
}

std::string DescribeKeywordOptions(const AddFlags& add_flags) {
  CLI::App app;
  add_flags(app);
  std::ostringstream text;
  for (const CLI::Option* option : KeywordOptions(app)) {
    text << "    " << KeywordOfOption(*option) << " (" << PythonType(*option);
    const std::string default_value = option->get_default_str();
    if (!default_value.empty()) text << ", default " << default_value;
    text << "): " << option->get_description() << "\n";
  }
  return text.str();
}

py::list ListKeywordOptions(const AddFlags& add_flags) {
  CLI::App app;
  add_flags(app);
  py::list list;
  for (const CLI::Option* option : KeywordOptions(app)) {
    py::dict entry;
    entry["name"] = KeywordOfOption(*option);
    entry["type"] = PythonType(*option);
    entry["default"] = option->get_default_str();
    entry["help"] = option->get_description();
    list.append(entry);
  }
  return list;
}

}  // namespace parallax::python
