#include "parallax/scene/database.h"

#include <sqlite3.h>

#include <set>

#include "parallax/scene/database_internal.h"
#include "parallax/util/check.h"

// Opening a database: its schema (COLMAP's tables and Parallax's own), the upgrade of an older
// one, transactions and counts. Cameras, images and features are in database_features.cc,
// matches and two-view geometries in database_matches.cc.

namespace parallax {

using internal::DescribeError;
using internal::Exec;
using internal::Statement;

namespace {

// COLMAP 3.8 writes its version number (3800) into `PRAGMA user_version`.
constexpr int kColmapUserVersion = 3800;

// One column of a COLMAP table: its name and the declaration after the name.
struct ColumnSpec {
  const char* name;
  const char* declaration;
  // Columns that COLMAP itself added by ALTER TABLE in later versions; an older database
  // without them is upgraded as COLMAP does rather than rejected.
  bool added_later = false;
  // Columns COLMAP 4 no longer has (the images' pose priors moved to its pose_priors table).
  bool dropped_in_colmap4 = false;
};

struct TableSpec {
  const char* name;
  std::vector<ColumnSpec> columns;
  // Table constraints after the columns (CHECK, FOREIGN KEY).
  std::vector<const char*> constraints;
};

// COLMAP 3.8's schema (src/base/database.cc, CreateTables): the same column names, types,
// constraints and order, so either program reads the other's files.
const std::vector<TableSpec>& ColmapTables() {
  static const std::vector<TableSpec> tables = {
      {"cameras",
       {{"camera_id", "INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL"},
        {"model", "INTEGER NOT NULL"},
        {"width", "INTEGER NOT NULL"},
        {"height", "INTEGER NOT NULL"},
        {"params", "BLOB"},
        {"prior_focal_length", "INTEGER NOT NULL"}},
       {}},
      {"images",
       {{"image_id", "INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL"},
        {"name", "TEXT NOT NULL UNIQUE"},
        {"camera_id", "INTEGER NOT NULL"},
        {"prior_qw", "REAL", false, true},
        {"prior_qx", "REAL", false, true},
        {"prior_qy", "REAL", false, true},
        {"prior_qz", "REAL", false, true},
        {"prior_tx", "REAL", false, true},
        {"prior_ty", "REAL", false, true},
        {"prior_tz", "REAL", false, true}},
       {"CONSTRAINT image_id_check CHECK(image_id >= 0 and image_id < 2147483647)",
        "FOREIGN KEY(camera_id) REFERENCES cameras(camera_id)"}},
      {"keypoints",
       {{"image_id", "INTEGER PRIMARY KEY NOT NULL"},
        {"rows", "INTEGER NOT NULL"},
        {"cols", "INTEGER NOT NULL"},
        {"data", "BLOB"}},
       {"FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE"}},
      {"descriptors",
       {{"image_id", "INTEGER PRIMARY KEY NOT NULL"},
        {"rows", "INTEGER NOT NULL"},
        {"cols", "INTEGER NOT NULL"},
        {"data", "BLOB"}},
       {"FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE"}},
      {"matches",
       {{"pair_id", "INTEGER PRIMARY KEY NOT NULL"},
        {"rows", "INTEGER NOT NULL"},
        {"cols", "INTEGER NOT NULL"},
        {"data", "BLOB"}},
       {}},
      {"two_view_geometries",
       {{"pair_id", "INTEGER PRIMARY KEY NOT NULL"},
        {"rows", "INTEGER NOT NULL"},
        {"cols", "INTEGER NOT NULL"},
        {"data", "BLOB"},
        {"config", "INTEGER NOT NULL"},
        {"F", "BLOB", true},
        {"E", "BLOB", true},
        {"H", "BLOB", true},
        {"qvec", "BLOB", true},
        {"tvec", "BLOB", true}},
       {}},
  };
  return tables;
}

// Parallax's own tables, which COLMAP ignores (it reads only its own): what each image's
// features were computed from, so that a rerun notices a photo edited or replaced since; and
// the colours under its keypoints, so that colouring a model decodes no image again.
const std::vector<TableSpec>& ParallaxTables() {
  static const std::vector<TableSpec> tables = {
      {"parallax_image_files",
       {{"image_id", "INTEGER PRIMARY KEY NOT NULL"},
        {"size", "INTEGER NOT NULL"},
        {"mtime_ns", "INTEGER NOT NULL"},
        {"content_hash", "TEXT NOT NULL"}},
       {"FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE"}},
      {"parallax_keypoint_colors",
       {{"image_id", "INTEGER PRIMARY KEY NOT NULL"},
        {"rows", "INTEGER NOT NULL"},
        {"data", "BLOB"}},
       {"FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE"}},
  };
  return tables;
}

std::string CreateTableSql(const TableSpec& table) {
  std::string sql = std::string("CREATE TABLE IF NOT EXISTS ") + table.name + " (";
  bool first = true;
  for (const ColumnSpec& column : table.columns) {
    sql += (first ? "" : ", ") + std::string(column.name) + " " + column.declaration;
    first = false;
  }
  for (const char* constraint : table.constraints) sql += std::string(", ") + constraint;
  return sql + ");";
}

// Whether the file has COLMAP 4's layout: rigs and frames, pose priors in their own table.
bool HasColmap4Layout(sqlite3* db, const std::filesystem::path& path) {
  Statement statement(db, path,
                      "SELECT 1 FROM sqlite_master WHERE type='table' AND name='pose_priors';");
  return statement.Step();
}

// Checks the schema against COLMAP's; with `apply`, creates what is missing (tables, the
// columns COLMAP added later, the name index). Returns true when nothing was missing.
// Throws InputError when an existing table lacks a column COLMAP always had.
// `colmap4`: the file has COLMAP 4's layout (HasColmap4Layout).
bool UpgradeSchema(sqlite3* db, const std::filesystem::path& path, bool colmap4, bool apply) {
  bool complete = true;
  std::set<std::string> existing_tables;
  bool has_name_index = false;
  {
    Statement statement(db, path, "SELECT type, name FROM sqlite_master;");
    while (statement.Step()) {
      if (statement.Text(0) == "table") existing_tables.insert(statement.Text(1));
      if (statement.Text(0) == "index" && statement.Text(1) == "index_name") has_name_index = true;
    }
  }
  const bool fresh = existing_tables.count("cameras") == 0 && existing_tables.count("images") == 0;
  // Databases of COLMAP before 3.5 call the table inlier_matches.
  if (existing_tables.count("inlier_matches") > 0 &&
      existing_tables.count("two_view_geometries") == 0) {
    complete = false;
    if (apply) Exec(db, path, "ALTER TABLE inlier_matches RENAME TO two_view_geometries;");
    existing_tables.insert("two_view_geometries");
  }
  for (const TableSpec& table : ColmapTables()) {
    if (existing_tables.count(table.name) == 0) {
      complete = false;
      if (apply) Exec(db, path, CreateTableSql(table));
      continue;
    }
    std::set<std::string> columns;
    Statement info(db, path, (std::string("PRAGMA table_info(") + table.name + ");").c_str());
    while (info.Step()) columns.insert(info.Text(1));
    for (const ColumnSpec& column : table.columns) {
      if (columns.count(column.name) > 0 || (colmap4 && column.dropped_in_colmap4)) continue;
      if (!column.added_later) {
        throw InputError(path.string() + ": not a COLMAP database: table '" + table.name +
                         "' has no column '" + column.name + "'");
      }
      complete = false;
      if (apply) {
        Exec(db, path,
             std::string("ALTER TABLE ") + table.name + " ADD COLUMN " + column.name + " " +
                 column.declaration + ";");
      }
    }
  }
  for (const TableSpec& table : ParallaxTables()) {
    if (existing_tables.count(table.name) > 0) continue;
    complete = false;
    if (apply) Exec(db, path, CreateTableSql(table));
  }
  if (!has_name_index) {
    complete = false;
    if (apply) Exec(db, path, "CREATE UNIQUE INDEX IF NOT EXISTS index_name ON images(name);");
  }
  if (fresh && apply) {
    Exec(db, path, "PRAGMA user_version = " + std::to_string(kColmapUserVersion) + ";");
  }
  return complete;
}

size_t CountRows(sqlite3* db, const std::filesystem::path& path, const char* sql) {
  Statement statement(db, path, sql);
  return statement.Step() ? static_cast<size_t>(statement.Int64(0)) : 0;
}

}  // namespace

namespace internal {

void Exec(sqlite3* db, const std::filesystem::path& path, const std::string& sql) {
  char* error = nullptr;
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK) {
    const std::string message = DescribeError(db, error != nullptr ? error : sqlite3_errmsg(db));
    sqlite3_free(error);
    throw InputError(path.string() + ": \"" + sql + "\" failed: " + message);
  }
}

}  // namespace internal

Database::Database(const std::filesystem::path& path) : path_(path) {
  if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) !=
      SQLITE_OK) {
    const std::string message = db_ != nullptr ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close_v2(db_);
    db_ = nullptr;
    throw InputError(path.string() + ": cannot open database: " + message);
  }
  try {
    sqlite3_busy_timeout(db_, 10000);
    // The first statement reads the header: a file that is not SQLite fails here.
    char* error = nullptr;
    if (sqlite3_exec(db_, "SELECT COUNT(*) FROM sqlite_master;", nullptr, nullptr, &error) !=
        SQLITE_OK) {
      const std::string message = error != nullptr ? error : sqlite3_errmsg(db_);
      sqlite3_free(error);
      if ((sqlite3_errcode(db_) & 0xff) == SQLITE_NOTADB) {
        throw InputError(path.string() + ": not a valid SQLite database (" + message + ")");
      }
      throw InputError(path.string() +
                       ": cannot read the database: " + DescribeError(db_, message));
    }
    // WAL: a killed writer leaves the committed state; the next opener replays the log.
    // synchronous=NORMAL keeps that guarantee for process crashes (not for power loss).
    Execute("PRAGMA journal_mode=WAL;");
    Execute("PRAGMA synchronous=NORMAL;");
    Execute("PRAGMA temp_store=MEMORY;");
    Execute("PRAGMA foreign_keys=ON;");

    // Check first and write only when something is missing, so that opening a database
    // that another connection is writing to does not wait for its lock.
    // The upgrade never adds COLMAP 4's tables, so the layout is known before it.
    colmap4_layout_ = HasColmap4Layout(db_, path_);
    if (!UpgradeSchema(db_, path_, colmap4_layout_, /*apply=*/false)) {
      DatabaseTransaction transaction(this, DatabaseTransaction::Nesting::kJoin);
      UpgradeSchema(db_, path_, colmap4_layout_, /*apply=*/true);
      transaction.Commit();
    }
  } catch (...) {
    sqlite3_close_v2(db_);
    db_ = nullptr;
    throw;
  }
}

Database::~Database() {
  if (db_ != nullptr) sqlite3_close_v2(db_);
}

void Database::Execute(const std::string& sql) const { Exec(db_, path_, sql); }

void Database::Checkpoint() { Execute("PRAGMA wal_checkpoint(TRUNCATE);"); }

// ----- Transactions -------------------------------------------------------------------------

DatabaseTransaction::DatabaseTransaction(Database* database)
    : DatabaseTransaction(database, Nesting::kRefuse) {}

DatabaseTransaction::DatabaseTransaction(Database* database, Nesting nesting)
    : database_(database) {
  PARALLAX_CHECK(database != nullptr);
  const bool open = sqlite3_get_autocommit(database->db_) == 0;
  PARALLAX_CHECK_MSG(!open || nesting == Nesting::kJoin, "nested transactions are not supported");
  owns_ = !open;
  // IMMEDIATE takes the write lock now, so a busy database fails here (after the busy timeout)
  // and not at a write halfway through.
  if (owns_) database_->Execute("BEGIN IMMEDIATE TRANSACTION;");
}

DatabaseTransaction::~DatabaseTransaction() {
  // Fails harmlessly when SQLite has already rolled back (a full disk, for one).
  if (owns_ && !committed_) sqlite3_exec(database_->db_, "ROLLBACK;", nullptr, nullptr, nullptr);
}

void DatabaseTransaction::Commit() {
  PARALLAX_CHECK_MSG(!committed_, "the transaction is already committed");
  if (owns_) database_->Execute("COMMIT;");
  committed_ = true;
}

// ----- Counts -------------------------------------------------------------------------------

size_t Database::NumCameras() const {
  return CountRows(db_, path_, "SELECT COUNT(*) FROM cameras;");
}
size_t Database::NumImages() const { return CountRows(db_, path_, "SELECT COUNT(*) FROM images;"); }
size_t Database::NumMatchedPairs() const {
  return CountRows(db_, path_, "SELECT COUNT(*) FROM matches;");
}
size_t Database::NumVerifiedPairs() const {
  return CountRows(db_, path_, "SELECT COUNT(*) FROM two_view_geometries;");
}

}  // namespace parallax
