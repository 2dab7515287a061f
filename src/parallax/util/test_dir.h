#pragma once

// For tests only (needs GoogleTest).

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <optional>
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

// An existing folder this process cannot create anything in: a read-only folder in `dir`
// (chmod 0555), or for root, whom permissions do not stop, a sysfs folder (read-only for
// everyone). Nothing when there is none.
inline std::optional<std::filesystem::path> UnwritableFolder(const ScopedTestDir& dir) {
  namespace fs = std::filesystem;
  if (geteuid() == 0) {
    const fs::path sys = "/sys/kernel";
    std::error_code error;
    if (!fs::is_directory(sys) || fs::create_directory(sys / "parallax_probe", error)) {
      return std::nullopt;
    }
    return sys;
  }
  const fs::path folder = dir.path() / "read_only";
  fs::create_directories(folder);
  fs::permissions(folder, fs::perms::owner_read | fs::perms::owner_exec);
  return folder;
}

}  // namespace parallax::test
