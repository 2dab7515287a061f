#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace parallax {

// Thrown by the PARALLAX_CHECK macros: a programming error (a broken precondition), not an
// expected failure. Tests catch it; the CLI turns it into a one-line error and exit code.
class CheckError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

// Thrown for bad user input (unreadable file, malformed text): the message names the file.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Bad input of one kind: a file or folder the user named does not exist (the Python module
// raises FileNotFoundError for it, ValueError for other input errors).
class MissingFileError : public InputError {
 public:
  using InputError::InputError;
};

namespace internal {
[[noreturn]] void ThrowCheckError(const char* file, int line, const char* expression,
                                  const std::string& message);

template <typename A, typename B>
std::string FormatComparison(const A& a, const B& b) {
  std::ostringstream stream;
  stream << "(" << a << " vs. " << b << ")";
  return stream.str();
}
}  // namespace internal

}  // namespace parallax

#define PARALLAX_CHECK(condition)                                                                \
  do {                                                                                           \
    if (!(condition)) ::parallax::internal::ThrowCheckError(__FILE__, __LINE__, #condition, ""); \
  } while (false)

#define PARALLAX_CHECK_MSG(condition, message)                              \
  do {                                                                      \
    if (!(condition)) {                                                     \
      std::ostringstream parallax_check_stream_;                            \
      parallax_check_stream_ << message;                                    \
      ::parallax::internal::ThrowCheckError(__FILE__, __LINE__, #condition, \
                                            parallax_check_stream_.str());  \
    }                                                                       \
  } while (false)

#define PARALLAX_CHECK_OP(op, a, b)                                                            \
  do {                                                                                         \
    if (!((a)op(b))) {                                                                         \
      ::parallax::internal::ThrowCheckError(__FILE__, __LINE__, #a " " #op " " #b,             \
                                            ::parallax::internal::FormatComparison((a), (b))); \
    }                                                                                          \
  } while (false)

#define PARALLAX_CHECK_EQ(a, b) PARALLAX_CHECK_OP(==, a, b)
#define PARALLAX_CHECK_NE(a, b) PARALLAX_CHECK_OP(!=, a, b)
#define PARALLAX_CHECK_LT(a, b) PARALLAX_CHECK_OP(<, a, b)
#define PARALLAX_CHECK_LE(a, b) PARALLAX_CHECK_OP(<=, a, b)
#define PARALLAX_CHECK_GT(a, b) PARALLAX_CHECK_OP(>, a, b)
#define PARALLAX_CHECK_GE(a, b) PARALLAX_CHECK_OP(>=, a, b)
