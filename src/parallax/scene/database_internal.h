#pragma once

// What the files of Database (database.cc: open, schema, transactions; database_features.cc:
// cameras, images and their features; database_matches.cc: matches and two-view geometries)
// share: SQLite statements and errors, and the blob layouts more than one of them reads.
// Not part of the scene layer's interface: include it from those files only.

#include <sqlite3.h>

#include <Eigen/Core>
#include <cstring>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>

#include "parallax/util/check.h"

namespace parallax {
namespace internal {

// SQLite's message, with what the user can do about the usual cause of a failed write or
// read (SQLite reports a write past `ulimit -f` as a disk I/O error).
inline std::string DescribeError(sqlite3* db, const std::string& message) {
  const int code = sqlite3_errcode(db) & 0xff;
  if (code == SQLITE_FULL || code == SQLITE_IOERR) {
    return message + " (is the disk full, or a file-size limit reached?)";
  }
  return message;
}

// Runs `sql` (no rows read); InputError naming the file and the statement when it fails.
void Exec(sqlite3* db, const std::filesystem::path& path, const std::string& sql);

// A prepared statement, finalized on scope exit. Errors throw InputError naming the file
// (a locked, read-only or corrupt database is a problem with the user's file).
class Statement {
 public:
  Statement(sqlite3* db, const std::filesystem::path& path, const char* sql)
      : db_(db), path_(path) {
    if (sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr) != SQLITE_OK) {
      Fail(std::string("cannot prepare \"") + sql + "\"");
    }
  }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  void BindInt64(int index, int64_t value) { Check(sqlite3_bind_int64(stmt_, index, value)); }
  void BindNull(int index) { Check(sqlite3_bind_null(stmt_, index)); }
  void BindDouble(int index, double value) { Check(sqlite3_bind_double(stmt_, index, value)); }
  // The text and blobs must outlive Step() (bound without copying).
  void BindText(int index, const std::string& text) {
    Check(sqlite3_bind_text(stmt_, index, text.c_str(), static_cast<int>(text.size()),
                            SQLITE_STATIC));
  }
  void BindBlob(int index, const void* data, size_t num_bytes) {
    if (num_bytes == 0) {
      Check(sqlite3_bind_zeroblob(stmt_, index, 0));
    } else {
      PARALLAX_CHECK_LE(num_bytes, static_cast<size_t>(std::numeric_limits<int>::max()));
      Check(sqlite3_bind_blob(stmt_, index, data, static_cast<int>(num_bytes), SQLITE_STATIC));
    }
  }

  // True while a row is available; false when done.
  bool Step(const char* what = "query") {
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    Fail(what);
  }

  int64_t Int64(int column) const { return sqlite3_column_int64(stmt_, column); }
  double Double(int column) const { return sqlite3_column_double(stmt_, column); }
  std::string Text(int column) const {
    const unsigned char* text = sqlite3_column_text(stmt_, column);
    return text == nullptr ? std::string() : std::string(reinterpret_cast<const char*>(text));
  }
  size_t NumBytes(int column) const {
    return static_cast<size_t>(sqlite3_column_bytes(stmt_, column));
  }
  const void* Blob(int column) const { return sqlite3_column_blob(stmt_, column); }

 private:
  void Check(int rc) {
    if (rc != SQLITE_OK) Fail("cannot bind a parameter");
  }
  [[noreturn]] void Fail(const std::string& what) const {
    throw InputError(path_.string() + ": " + what + ": " + DescribeError(db_, sqlite3_errmsg(db_)));
  }

  sqlite3* db_;
  const std::filesystem::path& path_;
  sqlite3_stmt* stmt_ = nullptr;
};

// A fixed-size double blob (F, E, H row-major; qvec; tvec; a pose prior's position), named
// `what` in the error. COLMAP writes empty blobs (pairs without inliers) and NULLs: those
// read as nullopt.
template <int kSize>
std::optional<Eigen::Matrix<double, kSize, 1>> ReadDoubles(const Statement& statement, int column,
                                                           const std::filesystem::path& path,
                                                           const char* what = "two-view geometry") {
  const size_t num_bytes = statement.NumBytes(column);
  if (num_bytes == 0) return std::nullopt;
  if (num_bytes != kSize * sizeof(double)) {
    throw InputError(path.string() + ": malformed " + what + " blob of " +
                     std::to_string(num_bytes) + " bytes (expected " +
                     std::to_string(kSize * sizeof(double)) + ")");
  }
  Eigen::Matrix<double, kSize, 1> values;
  std::memcpy(values.data(), statement.Blob(column), num_bytes);
  return values;
}

}  // namespace internal
}  // namespace parallax
