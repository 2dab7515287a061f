#pragma once

#include <pybind11/pybind11.h>
#include <CLI/CLI.hpp>

#include <functional>
#include <string>

namespace parallax::python {

// The keyword options of the pipeline functions are the command line's flags, parsed by the
// same CLI11 definitions (cli/pipeline_options_cli.h, cli/mapper_options_cli.h): `max_error=2`
// is `--max-error 2`, `preemptive=False` is `--no-preemptive`, `camera_params=[f, cx, cy]` is
// `--camera-params f,cx,cy`. Names, defaults, checks and error messages are one set for both.

// Adds a function's flags to `app`, bound to the options they set.
using AddFlags = std::function<void(CLI::App& app)>;

// Parses `options` as the flags of `app`. An unknown keyword is a TypeError as Python gives
// one; a value the flag refuses is a ValueError with the flag's own message.
void ParseKeywordOptions(const std::string& function_name, const pybind11::kwargs& options,
                         CLI::App& app);

// The flags of `add_flags` as a docstring section: one line per keyword with its type, default
// and help.
std::string DescribeKeywordOptions(const AddFlags& add_flags);

// The flags of `add_flags` as Python values: [{"name", "type", "default", "help"}, ...], for
// the type stubs and their test.
pybind11::list ListKeywordOptions(const AddFlags& add_flags);

}  // namespace parallax::python
