#include "parallax/util/check.h"

namespace parallax::internal {

void ThrowCheckError(const char* file, int line, const char* expression,
                     const std::string& message) {
  std::ostringstream stream;
  stream << "Check failed at " << file << ":" << line << ": " << expression;
  if (!message.empty()) stream << " " << message;
  throw CheckError(stream.str());
}

}  // namespace parallax::internal
