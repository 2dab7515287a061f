#include "parallax/util/file.h"

#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <system_error>

#include "parallax/util/check.h"

namespace parallax {

void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(std::ostream&)>& writer, bool binary) {
  const std::filesystem::path temp_path =
      path.string() + ".tmp-" + std::to_string(static_cast<long>(getpid()));
  {
    std::ofstream stream(temp_path, binary ? std::ios::binary | std::ios::out : std::ios::out);
    if (!stream) throw InputError(path.string() + ": cannot open for writing");
    errno = 0;
    writer(stream);
    stream.flush();
    if (!stream) {
      // The stream keeps no error code; errno still holds the failed write's (ENOSPC, EFBIG).
      const int write_error = errno;
      std::error_code ignored;
      std::filesystem::remove(temp_path, ignored);
      throw InputError(path.string() + ": write failed" +
                       (write_error != 0 ? std::string(": ") + std::strerror(write_error) : ""));
    }
  }
  std::error_code error;
  std::filesystem::rename(temp_path, path, error);
  if (error) {
    std::error_code ignored;
    std::filesystem::remove(temp_path, ignored);
    throw InputError(path.string() + ": cannot rename into place: " + error.message());
  }
}

void WriteTextFileAtomically(const std::filesystem::path& path, const std::string& content) {
  WriteFileAtomically(path, [&](std::ostream& stream) { stream << content; });
}

std::string ReadFileToString(const std::filesystem::path& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) ThrowCannotOpenForReading(path);
  std::ostringstream buffer;
  buffer << stream.rdbuf();
  if (stream.bad()) throw InputError(path.string() + ": read failed");
  return buffer.str();
}

void ThrowCannotOpenForReading(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::exists(path, error) && !error) {
    throw MissingFileError(path.string() + ": cannot open for reading: no such file");
  }
  throw InputError(path.string() + ": cannot open for reading");
}

std::vector<std::string> SplitLines(const std::string& text) {
  std::vector<std::string> lines;
  std::string line;
  std::istringstream stream(text);
  while (std::getline(stream, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(line);
  }
  return lines;
}

std::string Trim(const std::string& text) {
  const char* whitespace = " \t\r\n\f\v";
  const size_t first = text.find_first_not_of(whitespace);
  if (first == std::string::npos) return "";
  const size_t last = text.find_last_not_of(whitespace);
  return text.substr(first, last - first + 1);
}

void CreateDirectoryOrThrow(const std::filesystem::path& dir) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error || !std::filesystem::is_directory(dir)) {
    throw InputError(dir.string() + ": cannot create output folder" +
                     (error ? ": " + error.message() : ""));
  }
}

std::filesystem::path DataRoot() {
  const char* value = std::getenv("PARALLAX_DATA");
  if (value != nullptr && value[0] != '\0') return value;
#ifdef PARALLAX_SOURCE_DIR
  return std::filesystem::path(PARALLAX_SOURCE_DIR) / ".." / "shared" / "data";
#else
  return "../shared/data";
#endif
}

}  // namespace parallax
