#include "parallax/util/run_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "parallax/util/check.h"
#include "parallax/util/file.h"

namespace parallax {

RunLock::RunLock(const std::filesystem::path& lock_path, const std::string& what) {
  fd_ = open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    throw InputError(lock_path.string() + ": cannot create the lock file: " + std::strerror(errno));
  }
  if (flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    std::string holder;
    if (error == EWOULDBLOCK) {
      // The holder wrote its id right after locking; it may not have yet.
      const std::string pid = Trim(ReadFileToString(lock_path));
      holder = pid.empty() ? "another parallax run" : "another parallax run (process " + pid + ")";
    }
    close(fd_);
    fd_ = -1;
    if (error != EWOULDBLOCK) {
      throw InputError(lock_path.string() + ": cannot lock: " + std::strerror(error));
    }
    throw InputError(what + ": in use by " + holder +
                     "; wait for it to finish or stop it, then run this command again");
  }
  const std::string pid = std::to_string(static_cast<long>(getpid())) + "\n";
  // Best effort: the id only makes the other run's message more useful.
  if (ftruncate(fd_, 0) == 0) {
    [[maybe_unused]] const ssize_t written = pwrite(fd_, pid.data(), pid.size(), 0);
  }
}

RunLock::~RunLock() {
  if (fd_ >= 0) close(fd_);  // Closing the descriptor releases the lock.
}

std::filesystem::path DatabaseLockPath(const std::filesystem::path& database_path) {
  return database_path.string() + ".lock";
}

std::filesystem::path OutputLockPath(const std::filesystem::path& output_dir) {
  return output_dir / ".parallax.lock";
}

}  // namespace parallax
