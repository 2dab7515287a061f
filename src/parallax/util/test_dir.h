#pragma once

// For tests only (needs GoogleTest).

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <system_error>

namespace parallax::test {

// A fresh folder under the system temp folder, named after `prefix`, the process and the
// running test, and removed with everything in it by the destructor. Fixtures hold one as a
// member, so each test case starts from an empty folder.
class ScopedTestDir {
 public:
  explicit ScopedTestDir(const std::string& prefix) {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ =
        std::filesystem::temp_directory_path() / (prefix + "_" + std::to_string(getpid()) + "_" +
                                                  (info != nullptr ? info->name() : "suite"));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScopedTestDir() {
    std::error_code error;
    std::filesystem::remove_all(path_, error);
  }
  ScopedTestDir(const ScopedTestDir&) = delete;
  ScopedTestDir& operator=(const ScopedTestDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace parallax::test
