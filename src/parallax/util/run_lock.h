#pragma once

#include <filesystem>
#include <string>

namespace parallax {

// One run at a time per output folder and per database: an exclusive flock(2) on a lock file,
// held for the object's lifetime. The kernel releases it when the process ends, however it
// ends, so a killed run never leaves a stale lock; the file itself stays and is reused.
class RunLock {
 public:
  // Takes the lock on `lock_path` (created if missing) and writes this process's id into it.
  // When another process holds it, throws InputError before anything else is touched:
  // "<what>: in use by another parallax run (process <pid>); ...".
  RunLock(const std::filesystem::path& lock_path, const std::string& what);
  ~RunLock();
  RunLock(const RunLock&) = delete;
  RunLock& operator=(const RunLock&) = delete;

 private:
  int fd_ = -1;
};

// The lock file of a database: "<database>.lock" beside it (SQLite's own files are
// "<database>-wal" and "<database>-shm").
std::filesystem::path DatabaseLockPath(const std::filesystem::path& database_path);

// The lock file of an output folder: "<folder>/.parallax.lock".
std::filesystem::path OutputLockPath(const std::filesystem::path& output_dir);

}  // namespace parallax
