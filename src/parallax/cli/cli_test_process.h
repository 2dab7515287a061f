#pragma once

// Running the `parallax` binary from end-to-end tests (header only: cli/*.cc other than
// tests are compiled into the binary). The binary's path comes from PARALLAX_BINARY, set by
// CTest. Processes are spawned without a shell so that a crash shows as the signal that
// ended the process, and every wait has a time limit so that a hang fails the test.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "parallax/util/file.h"
#include "parallax/util/test_dir.h"

extern char** environ;

namespace parallax::test {

namespace fs = std::filesystem;

struct ProcessResult {
  int exit_code = -1;      // Exit status when the process exited.
  int signal = 0;          // The signal that ended it (a crash, or our kill), else 0.
  bool timed_out = false;  // Killed by us at the time limit.
  std::string out;         // Its stdout.
  std::string err;         // Its stderr.
  double seconds = 0;
  // Exited on its own (no signal, no time-out) with this code.
  bool ExitedWith(int code) const { return signal == 0 && !timed_out && exit_code == code; }
};

// A running child process with stdout and stderr redirected to files.
class ChildProcess {
 public:
  ChildProcess(const std::vector<std::string>& argv, const fs::path& out_path,
               const fs::path& err_path)
      : out_path_(out_path), err_path_(err_path), start_(std::chrono::steady_clock::now()) {
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out_path.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_path.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    std::vector<char*> args;
    for (const std::string& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
    args.push_back(nullptr);
    const int error = posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (error != 0) {
      ADD_FAILURE() << "cannot start " << argv[0] << ": " << std::strerror(error);
      pid_ = -1;
    }
  }
  ~ChildProcess() {
    if (pid_ > 0 && !finished_) {
      kill(pid_, SIGKILL);
      int status = 0;
      waitpid(pid_, &status, 0);
    }
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t Pid() const { return pid_; }
  bool Running() {
    if (pid_ <= 0 || finished_) return false;
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) Finish(status);
    return !finished_;
  }
  std::string Stderr() const { return ReadIfExists(err_path_); }

  // Waits for the end, killing the process (timed_out) after `timeout_seconds`.
  ProcessResult Wait(double timeout_seconds) {
    const auto deadline =
        start_ + std::chrono::milliseconds(static_cast<int64_t>(timeout_seconds * 1000));
    while (Running()) {
      if (std::chrono::steady_clock::now() > deadline) {
        result_.timed_out = true;
        KillAndReap(SIGKILL);
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    result_.out = ReadIfExists(out_path_);
    result_.err = ReadIfExists(err_path_);
    return result_;
  }

  // Sends `signal` and waits for the process to end.
  void KillAndReap(int signal) {
    if (pid_ <= 0 || finished_) return;
    kill(pid_, signal);
    int status = 0;
    waitpid(pid_, &status, 0);
    Finish(status);
  }

 private:
  static std::string ReadIfExists(const fs::path& path) {
    std::error_code error;
    return fs::exists(path, error) ? ReadFileToString(path) : std::string();
  }
  void Finish(int status) {
    finished_ = true;
    result_.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    if (WIFEXITED(status)) result_.exit_code = WEXITSTATUS(status);
    if (WIFSIGNALED(status)) result_.signal = WTERMSIG(status);
  }

  fs::path out_path_, err_path_;
  std::chrono::steady_clock::time_point start_;
  pid_t pid_ = -1;
  bool finished_ = false;
  ProcessResult result_;
};

// The binary under test, or empty when PARALLAX_BINARY is unset (tests then skip).
inline std::string ParallaxBinary() {
  const char* binary = std::getenv("PARALLAX_BINARY");
  if (binary == nullptr || !fs::exists(binary)) return "";
  return binary;
}

// Runs `parallax <arguments>` to the end (at most `timeout_seconds`), output files in `dir`.
inline ProcessResult RunParallax(const std::vector<std::string>& arguments, const fs::path& dir,
                                 double timeout_seconds = 120) {
  std::vector<std::string> argv = {ParallaxBinary()};
  argv.insert(argv.end(), arguments.begin(), arguments.end());
  ChildProcess child(argv, dir / "stdout.txt", dir / "stderr.txt");
  return child.Wait(timeout_seconds);
}

// Runs `parallax <arguments>` through /bin/sh after the shell commands `shell_prefix` (such
// as "ulimit -f 400"), which apply to it alone.
inline ProcessResult RunParallaxAfter(const std::string& shell_prefix,
                                      const std::vector<std::string>& arguments,
                                      const fs::path& dir, double timeout_seconds = 300) {
  std::string command = shell_prefix + "; exec '" + ParallaxBinary() + "'";
  for (const std::string& argument : arguments) command += " '" + argument + "'";
  ChildProcess child({"/bin/sh", "-c", command}, dir / "stdout.txt", dir / "stderr.txt");
  return child.Wait(timeout_seconds);
}

// Renders a small synthetic scene with `parallax synth` (images view_0001.png..., K.txt,
// synth_par.txt, gt/) and fails the test when it cannot.
// `layout`: ring (neighbours 360/num_views degrees apart) or sequence (a walk past temples,
// which a few views already reconstruct).
inline void RenderSyntheticScene(const fs::path& dir, int num_views, int width, int height,
                                 const fs::path& log_dir, const std::string& layout = "ring") {
  const ProcessResult result = RunParallax(
      {"synth", "--output", dir.string(), "--views", std::to_string(num_views), "--width",
       std::to_string(width), "--height", std::to_string(height), "--layout", layout, "-q"},
      log_dir, 300);
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
}

}  // namespace parallax::test
