#pragma once

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

namespace parallax {

// Writes a file atomically: the content goes to "<path>.tmp-<pid>" and is renamed over `path`
// only once complete, so an interrupted run never leaves a half-written output.
// Throws InputError naming the path when it cannot be written.
void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(std::ostream&)>& writer, bool binary = false);
void WriteTextFileAtomically(const std::filesystem::path& path, const std::string& content);

// Reads a whole file; throws InputError naming the path on failure.
std::string ReadFileToString(const std::filesystem::path& path);

// Throws "<path>: cannot open for reading", as MissingFileError when nothing is there and as
// InputError otherwise (a folder, no permission).
[[noreturn]] void ThrowCannotOpenForReading(const std::filesystem::path& path);

// Splits text into lines, dropping '\r' (Windows line endings in the datasets' text files).
std::vector<std::string> SplitLines(const std::string& text);

// Trims ASCII whitespace at both ends.
std::string Trim(const std::string& text);

// Creates `dir` (and parents) or throws InputError with a one-line reason.
void CreateDirectoryOrThrow(const std::filesystem::path& dir);

// The datasets folder: $PARALLAX_DATA, or ../shared/data beside the source checkout when unset.
std::filesystem::path DataRoot();

}  // namespace parallax
