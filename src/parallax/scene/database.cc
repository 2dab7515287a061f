#include "parallax/scene/database.h"

#include <sqlite3.h>

#include <Eigen/LU>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>

#include "parallax/util/check.h"

namespace parallax {
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

// SQLite's message, with what the user can do about the usual cause of a failed write or
// read (SQLite reports a write past `ulimit -f` as a disk I/O error).
std::string DescribeError(sqlite3* db, const std::string& message) {
  const int code = sqlite3_errcode(db) & 0xff;
  if (code == SQLITE_FULL || code == SQLITE_IOERR) {
    return message + " (is the disk full, or a file-size limit reached?)";
  }
  return message;
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

// Keypoint blobs are rows x 6 float32 (x, y, a11, a12, a21, a22); COLMAP also reads the older
// 2-column (x, y) and 4-column (x, y, scale, orientation) layouts, and so do we.
constexpr int kKeypointCols = 6;

FeatureKeypoints KeypointsFromBlob(const float* data, size_t rows, size_t cols,
                                   const std::filesystem::path& path, image_t image_id) {
  if (cols != 2 && cols != 4 && cols != 6) {
    throw InputError(path.string() + ": keypoints of image " + std::to_string(image_id) + " have " +
                     std::to_string(cols) + " columns (expected 2, 4 or 6)");
  }
  FeatureKeypoints keypoints(rows);
  for (size_t i = 0; i < rows; ++i) {
    const float* row = data + i * cols;
    if (cols == 2) {
      keypoints[i] = FeatureKeypoint(row[0], row[1]);
    } else if (cols == 4) {
      keypoints[i] = FeatureKeypoint(row[0], row[1], row[2], row[3]);
    } else {
      FeatureKeypoint& keypoint = keypoints[i];
      keypoint.x = row[0];
      keypoint.y = row[1];
      keypoint.a11 = row[2];
      keypoint.a12 = row[3];
      keypoint.a21 = row[4];
      keypoint.a22 = row[5];
    }
  }
  return keypoints;
}

// Matches as a rows x 2 uint32 blob, with the columns swapped when the pair is.
std::vector<uint32_t> MatchesToBlob(const FeatureMatches& matches, bool swap) {
  std::vector<uint32_t> blob(2 * matches.size());
  for (size_t i = 0; i < matches.size(); ++i) {
    blob[2 * i + 0] = swap ? matches[i].point2D_idx2 : matches[i].point2D_idx1;
    blob[2 * i + 1] = swap ? matches[i].point2D_idx1 : matches[i].point2D_idx2;
  }
  return blob;
}

// Reads (rows, cols, data) starting at `column` as matches.
FeatureMatches MatchesFromRow(const Statement& statement, int column, bool swap,
                              const std::filesystem::path& path) {
  const size_t rows = static_cast<size_t>(statement.Int64(column));
  const size_t cols = static_cast<size_t>(statement.Int64(column + 1));
  const size_t num_bytes = statement.NumBytes(column + 2);
  if ((rows > 0 && cols != 2) || num_bytes != rows * cols * sizeof(uint32_t)) {
    throw InputError(path.string() + ": malformed matches blob (" + std::to_string(rows) + "x" +
                     std::to_string(cols) + ", " + std::to_string(num_bytes) + " bytes)");
  }
  FeatureMatches matches(rows);
  if (rows == 0) return matches;
  std::vector<uint32_t> blob(2 * rows);
  std::memcpy(blob.data(), statement.Blob(column + 2), num_bytes);
  for (size_t i = 0; i < rows; ++i) {
    matches[i].point2D_idx1 = blob[2 * i + (swap ? 1 : 0)];
    matches[i].point2D_idx2 = blob[2 * i + (swap ? 0 : 1)];
  }
  return matches;
}

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

Eigen::Matrix3d MatrixFromRowMajor(const std::optional<Eigen::Matrix<double, 9, 1>>& values) {
  if (!values) return Eigen::Matrix3d::Zero();
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(values->data());
}

// The geometry of the pair seen from the other image: COLMAP's TwoViewGeometry::Invert.
TwoViewGeometry InvertTwoViewGeometry(const TwoViewGeometry& geometry) {
  TwoViewGeometry inverted = geometry;
  inverted.F = geometry.F.transpose();
  inverted.E = geometry.E.transpose();
  // A zero (unset) H stays zero rather than becoming NaN.
  if (!geometry.H.isZero(0)) inverted.H = geometry.H.inverse();
  inverted.cam2_from_cam1 = geometry.cam2_from_cam1.Inverse();
  for (FeatureMatch& match : inverted.inlier_matches) {
    std::swap(match.point2D_idx1, match.point2D_idx2);
  }
  return inverted;
}

// Reads columns (rows, cols, data, config, F, E, H, qvec, tvec) starting at `column`.
TwoViewGeometry TwoViewGeometryFromRow(const Statement& statement, int column,
                                       const std::filesystem::path& path) {
  TwoViewGeometry geometry;
  geometry.inlier_matches = MatchesFromRow(statement, column, false, path);
  geometry.config = static_cast<int>(statement.Int64(column + 3));
  geometry.F = MatrixFromRowMajor(ReadDoubles<9>(statement, column + 4, path));
  geometry.E = MatrixFromRowMajor(ReadDoubles<9>(statement, column + 5, path));
  geometry.H = MatrixFromRowMajor(ReadDoubles<9>(statement, column + 6, path));
  if (const auto qvec = ReadDoubles<4>(statement, column + 7, path); qvec && !qvec->isZero(0)) {
    geometry.cam2_from_cam1.rotation =
        Eigen::Quaterniond((*qvec)(0), (*qvec)(1), (*qvec)(2), (*qvec)(3));
  }
  if (const auto tvec = ReadDoubles<3>(statement, column + 8, path)) {
    geometry.cam2_from_cam1.translation = *tvec;
  }
  return geometry;
}

Camera CameraFromRow(const Statement& statement, const std::filesystem::path& path) {
  Camera camera;
  camera.camera_id = static_cast<camera_t>(statement.Int64(0));
  const int model = static_cast<int>(statement.Int64(1));
  if (!ExistsCameraModel(model)) {
    throw InputError(path.string() + ": camera " + std::to_string(camera.camera_id) +
                     " has unsupported model id " + std::to_string(model));
  }
  camera.model_id = static_cast<CameraModelId>(model);
  camera.width = static_cast<size_t>(statement.Int64(2));
  camera.height = static_cast<size_t>(statement.Int64(3));
  const size_t num_bytes = statement.NumBytes(4);
  if (num_bytes != CameraModelNumParams(camera.model_id) * sizeof(double)) {
    throw InputError(path.string() + ": camera " + std::to_string(camera.camera_id) + " has " +
                     std::to_string(num_bytes / sizeof(double)) + " params, " + camera.ModelName() +
                     " needs " + std::to_string(CameraModelNumParams(camera.model_id)));
  }
  camera.params.resize(num_bytes / sizeof(double));
  if (num_bytes > 0) std::memcpy(camera.params.data(), statement.Blob(4), num_bytes);
  camera.has_prior_focal_length = statement.Int64(5) != 0;
  return camera;
}

Image ImageFromRow(const Statement& statement) {
  Image image;
  image.image_id = static_cast<image_t>(statement.Int64(0));
  image.name = statement.Text(1);
  image.camera_id = static_cast<camera_t>(statement.Int64(2));
  return image;
}

void Exec(sqlite3* db, const std::filesystem::path& path, const std::string& sql) {
  char* error = nullptr;
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK) {
    const std::string message = DescribeError(db, error != nullptr ? error : sqlite3_errmsg(db));
    sqlite3_free(error);
    throw InputError(path.string() + ": \"" + sql + "\" failed: " + message);
  }
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

}  // namespace

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

// ----- Cameras ------------------------------------------------------------------------------

void Database::RefuseNewImagesInColmap4Layout() const {
  if (!colmap4_layout_) return;
  throw InputError(path_.string() +
                   ": a COLMAP 4 database; Parallax reads its features and matches (match, "
                   "mapper) but does not add cameras or images to it: extract into a new database");
}

camera_t Database::WriteCamera(const Camera& camera, bool use_camera_id) {
  RefuseNewImagesInColmap4Layout();
  PARALLAX_CHECK_MSG(camera.VerifyParams(), "camera " << camera.camera_id << " has invalid params");
  Statement statement(db_, path_,
                      "INSERT INTO cameras(camera_id, model, width, height, params, "
                      "prior_focal_length) VALUES(?, ?, ?, ?, ?, ?);");
  if (use_camera_id) {
    PARALLAX_CHECK_NE(camera.camera_id, kInvalidCameraId);
    statement.BindInt64(1, camera.camera_id);
  } else {
    statement.BindNull(1);
  }
  statement.BindInt64(2, static_cast<int>(camera.model_id));
  statement.BindInt64(3, static_cast<int64_t>(camera.width));
  statement.BindInt64(4, static_cast<int64_t>(camera.height));
  statement.BindBlob(5, camera.params.data(), camera.params.size() * sizeof(double));
  statement.BindInt64(6, camera.has_prior_focal_length ? 1 : 0);
  statement.Step("cannot write camera");
  return static_cast<camera_t>(sqlite3_last_insert_rowid(db_));
}

void Database::UpdateCamera(const Camera& camera) {
  PARALLAX_CHECK_MSG(camera.VerifyParams(), "camera " << camera.camera_id << " has invalid params");
  Statement statement(db_, path_,
                      "UPDATE cameras SET model=?, width=?, height=?, params=?, "
                      "prior_focal_length=? WHERE camera_id=?;");
  statement.BindInt64(1, static_cast<int>(camera.model_id));
  statement.BindInt64(2, static_cast<int64_t>(camera.width));
  statement.BindInt64(3, static_cast<int64_t>(camera.height));
  statement.BindBlob(4, camera.params.data(), camera.params.size() * sizeof(double));
  statement.BindInt64(5, camera.has_prior_focal_length ? 1 : 0);
  statement.BindInt64(6, camera.camera_id);
  statement.Step("cannot update camera");
  PARALLAX_CHECK_MSG(sqlite3_changes(db_) == 1, "no camera " << camera.camera_id);
}

bool Database::ExistsCamera(camera_t camera_id) const {
  Statement statement(db_, path_, "SELECT 1 FROM cameras WHERE camera_id=?;");
  statement.BindInt64(1, camera_id);
  return statement.Step();
}

Camera Database::ReadCamera(camera_t camera_id) const {
  Statement statement(db_, path_,
                      "SELECT camera_id, model, width, height, params, prior_focal_length "
                      "FROM cameras WHERE camera_id=?;");
  statement.BindInt64(1, camera_id);
  PARALLAX_CHECK_MSG(statement.Step(), "no camera " << camera_id << " in " << path_.string());
  return CameraFromRow(statement, path_);
}

std::vector<Camera> Database::ReadAllCameras() const {
  Statement statement(db_, path_,
                      "SELECT camera_id, model, width, height, params, prior_focal_length "
                      "FROM cameras ORDER BY camera_id;");
  std::vector<Camera> cameras;
  while (statement.Step()) cameras.push_back(CameraFromRow(statement, path_));
  return cameras;
}

// ----- Images -------------------------------------------------------------------------------

image_t Database::WriteImage(const std::string& name, camera_t camera_id) {
  RefuseNewImagesInColmap4Layout();
  // Pose priors are left NULL, as COLMAP writes them when unknown.
  Statement statement(db_, path_,
                      "INSERT INTO images(image_id, name, camera_id) VALUES(NULL, ?, ?);");
  statement.BindText(1, name);
  statement.BindInt64(2, camera_id);
  statement.Step(("cannot write image '" + name + "'").c_str());
  return static_cast<image_t>(sqlite3_last_insert_rowid(db_));
}

bool Database::ExistsImage(image_t image_id) const {
  Statement statement(db_, path_, "SELECT 1 FROM images WHERE image_id=?;");
  statement.BindInt64(1, image_id);
  return statement.Step();
}

std::optional<image_t> Database::ImageIdByName(const std::string& name) const {
  Statement statement(db_, path_, "SELECT image_id FROM images WHERE name=?;");
  statement.BindText(1, name);
  if (!statement.Step()) return std::nullopt;
  return static_cast<image_t>(statement.Int64(0));
}

Image Database::ReadImage(image_t image_id) const {
  Statement statement(db_, path_, "SELECT image_id, name, camera_id FROM images WHERE image_id=?;");
  statement.BindInt64(1, image_id);
  PARALLAX_CHECK_MSG(statement.Step(), "no image " << image_id << " in " << path_.string());
  return ImageFromRow(statement);
}

std::vector<Image> Database::ReadAllImages() const {
  Statement statement(db_, path_,
                      "SELECT image_id, name, camera_id FROM images ORDER BY image_id;");
  std::vector<Image> images;
  while (statement.Step()) images.push_back(ImageFromRow(statement));
  return images;
}

// ----- Keypoints and descriptors ------------------------------------------------------------

void Database::WriteKeypoints(image_t image_id, const FeatureKeypoints& keypoints) {
  std::vector<float> blob(kKeypointCols * keypoints.size());
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const FeatureKeypoint& keypoint = keypoints[i];
    float* row = blob.data() + kKeypointCols * i;
    row[0] = keypoint.x;
    row[1] = keypoint.y;
    row[2] = keypoint.a11;
    row[3] = keypoint.a12;
    row[4] = keypoint.a21;
    row[5] = keypoint.a22;
  }
  Statement statement(db_, path_,
                      "INSERT INTO keypoints(image_id, rows, cols, data) VALUES(?, ?, ?, ?);");
  statement.BindInt64(1, image_id);
  statement.BindInt64(2, static_cast<int64_t>(keypoints.size()));
  statement.BindInt64(3, kKeypointCols);
  statement.BindBlob(4, blob.data(), blob.size() * sizeof(float));
  statement.Step(("cannot write keypoints of image " + std::to_string(image_id)).c_str());
}

void Database::WriteDescriptors(image_t image_id, const FeatureDescriptors& descriptors) {
  Statement statement(db_, path_,
                      "INSERT INTO descriptors(image_id, rows, cols, data) VALUES(?, ?, ?, ?);");
  statement.BindInt64(1, image_id);
  statement.BindInt64(2, descriptors.rows());
  statement.BindInt64(3, descriptors.cols());
  // Row-major, one byte per element: the blob is the matrix memory.
  statement.BindBlob(4, descriptors.data(), static_cast<size_t>(descriptors.size()));
  statement.Step(("cannot write descriptors of image " + std::to_string(image_id)).c_str());
}

image_t Database::WriteImageWithFeatures(const std::string& name, camera_t camera_id,
                                         const FeatureKeypoints& keypoints,
                                         const FeatureDescriptors& descriptors,
                                         const std::optional<ImageFileFingerprint>& fingerprint,
                                         const std::optional<GeodeticPosition>& gps_prior,
                                         const std::optional<KeypointColors>& colors) {
  PARALLAX_CHECK_EQ(keypoints.size(), static_cast<size_t>(descriptors.rows()));
  DatabaseTransaction transaction(this, DatabaseTransaction::Nesting::kJoin);
  const image_t image_id = WriteImage(name, camera_id);
  WriteKeypoints(image_id, keypoints);
  WriteDescriptors(image_id, descriptors);
  if (fingerprint) WriteImageFileFingerprint(image_id, *fingerprint);
  if (gps_prior) WriteImageGpsPrior(image_id, *gps_prior);
  if (colors) WriteKeypointColors(image_id, *colors);
  transaction.Commit();
  return image_id;
}

void Database::WriteImageGpsPrior(image_t image_id, const GeodeticPosition& position) {
  Statement statement(
      db_, path_, "UPDATE images SET prior_tx = ?, prior_ty = ?, prior_tz = ? WHERE image_id = ?;");
  statement.BindDouble(1, position.latitude);
  statement.BindDouble(2, position.longitude);
  statement.BindDouble(3, position.altitude);
  statement.BindInt64(4, image_id);
  statement.Step("cannot write an image's GPS prior");
}

std::vector<std::pair<image_t, GeodeticPosition>> Database::ReadImageGpsPriors() const {
  if (colmap4_layout_) return ReadColmap4GpsPriors();
  Statement statement(db_, path_,
                      "SELECT image_id, prior_tx, prior_ty, prior_tz FROM images WHERE prior_tx IS "
                      "NOT NULL AND prior_ty IS NOT NULL ORDER BY image_id;");
  std::vector<std::pair<image_t, GeodeticPosition>> priors;
  while (statement.Step()) {
    const GeodeticPosition position{statement.Double(1), statement.Double(2), statement.Double(3)};
    priors.emplace_back(static_cast<image_t>(statement.Int64(0)), position);
  }
  return priors;
}

std::vector<std::pair<image_t, GeodeticPosition>> Database::ReadColmap4GpsPriors() const {
  // COLMAP 4: a camera image's prior (sensor type 0, data id = image id) in WGS84
  // (coordinate system 0) is latitude, longitude and altitude as three doubles.
  Statement statement(db_, path_,
                      "SELECT corr_data_id, position FROM pose_priors WHERE corr_sensor_type = 0 "
                      "AND coordinate_system = 0 ORDER BY corr_data_id;");
  std::vector<std::pair<image_t, GeodeticPosition>> priors;
  while (statement.Step()) {
    const auto position = ReadDoubles<3>(statement, 1, path_, "pose prior position");
    if (!position || !std::isfinite(position->x()) || !std::isfinite(position->y())) continue;
    priors.emplace_back(static_cast<image_t>(statement.Int64(0)),
                        GeodeticPosition{position->x(), position->y(), position->z()});
  }
  return priors;
}

void Database::WriteImageFileFingerprint(image_t image_id,
                                         const ImageFileFingerprint& fingerprint) {
  Statement statement(db_, path_,
                      "INSERT OR REPLACE INTO parallax_image_files(image_id, size, mtime_ns, "
                      "content_hash) VALUES(?, ?, ?, ?);");
  statement.BindInt64(1, image_id);
  statement.BindInt64(2, static_cast<int64_t>(fingerprint.size));
  statement.BindInt64(3, fingerprint.mtime_ns);
  statement.BindText(4, fingerprint.content_hash);
  statement.Step("cannot write an image file fingerprint");
}

std::optional<ImageFileFingerprint> Database::ReadImageFileFingerprint(image_t image_id) const {
  Statement statement(
      db_, path_,
      "SELECT size, mtime_ns, content_hash FROM parallax_image_files WHERE image_id=?;");
  statement.BindInt64(1, image_id);
  if (!statement.Step()) return std::nullopt;
  ImageFileFingerprint fingerprint;
  fingerprint.size = static_cast<uint64_t>(statement.Int64(0));
  fingerprint.mtime_ns = statement.Int64(1);
  fingerprint.content_hash = statement.Text(2);
  return fingerprint;
}

void Database::WriteKeypointColors(image_t image_id, const KeypointColors& colors) {
  PARALLAX_CHECK_EQ(colors.size() % 3, 0u);
  Statement statement(db_, path_,
                      "INSERT OR REPLACE INTO parallax_keypoint_colors(image_id, rows, data) "
                      "VALUES(?, ?, ?);");
  statement.BindInt64(1, image_id);
  statement.BindInt64(2, static_cast<int64_t>(colors.size() / 3));
  statement.BindBlob(3, colors.data(), colors.size());
  statement.Step(("cannot write keypoint colours of image " + std::to_string(image_id)).c_str());
}

std::optional<KeypointColors> Database::ReadKeypointColors(image_t image_id) const {
  Statement statement(db_, path_,
                      "SELECT rows, data FROM parallax_keypoint_colors WHERE image_id=?;");
  statement.BindInt64(1, image_id);
  if (!statement.Step()) return std::nullopt;
  const int64_t rows = statement.Int64(0);
  const size_t num_bytes = statement.NumBytes(1);
  if (rows < 0 || num_bytes != 3 * static_cast<size_t>(rows)) {
    throw InputError(path_.string() + ": malformed keypoint colours of image " +
                     std::to_string(image_id) + " (" + std::to_string(num_bytes) + " bytes for " +
                     std::to_string(rows) + " keypoints)");
  }
  const auto* data = static_cast<const uint8_t*>(statement.Blob(1));
  return KeypointColors(data, data + num_bytes);
}

void Database::DeleteImage(image_t image_id) {
  DatabaseTransaction transaction(this, DatabaseTransaction::Nesting::kJoin);
  camera_t camera_id = kInvalidCameraId;
  {
    Statement statement(db_, path_, "SELECT camera_id FROM images WHERE image_id=?;");
    statement.BindInt64(1, image_id);
    if (!statement.Step()) return;  // Nothing stored.
    camera_id = static_cast<camera_t>(statement.Int64(0));
  }
  // Pairs hold the image as either id of pair_id = id1 * kMaxNumImages + id2 (ImagePairToPairId).
  for (const std::string table : {"matches", "two_view_geometries"}) {
    const std::string sql =
        "DELETE FROM " + table + " WHERE pair_id / ?2 = ?1 OR pair_id % ?2 = ?1;";
    Statement statement(db_, path_, sql.c_str());
    statement.BindInt64(1, image_id);
    statement.BindInt64(2, static_cast<int64_t>(kMaxNumImages));
    statement.Step("cannot delete the pairs of an image");
  }
  for (const std::string table :
       {"keypoints", "descriptors", "parallax_image_files", "parallax_keypoint_colors", "images"}) {
    const std::string sql = "DELETE FROM " + table + " WHERE image_id = ?1;";
    Statement statement(db_, path_, sql.c_str());
    statement.BindInt64(1, image_id);
    statement.Step("cannot delete an image");
  }
  // A camera of its own goes with it; a shared one stays.
  Statement camera(db_, path_,
                   "DELETE FROM cameras WHERE camera_id = ?1 AND NOT EXISTS "
                   "(SELECT 1 FROM images WHERE camera_id = ?1);");
  camera.BindInt64(1, camera_id);
  camera.Step("cannot delete an unused camera");
  transaction.Commit();
}

bool Database::ExistsKeypoints(image_t image_id) const {
  Statement statement(db_, path_, "SELECT 1 FROM keypoints WHERE image_id=?;");
  statement.BindInt64(1, image_id);
  return statement.Step();
}

bool Database::ExistsDescriptors(image_t image_id) const {
  Statement statement(db_, path_, "SELECT 1 FROM descriptors WHERE image_id=?;");
  statement.BindInt64(1, image_id);
  return statement.Step();
}

FeatureKeypoints Database::ReadKeypoints(image_t image_id) const {
  Statement statement(db_, path_, "SELECT rows, cols, data FROM keypoints WHERE image_id=?;");
  statement.BindInt64(1, image_id);
  if (!statement.Step()) return {};
  const size_t rows = static_cast<size_t>(statement.Int64(0));
  const size_t cols = static_cast<size_t>(statement.Int64(1));
  const size_t num_bytes = statement.NumBytes(2);
  if (num_bytes != rows * cols * sizeof(float)) {
    throw InputError(path_.string() + ": keypoints of image " + std::to_string(image_id) +
                     ": blob of " + std::to_string(num_bytes) + " bytes for " +
                     std::to_string(rows) + "x" + std::to_string(cols) + " floats");
  }
  if (rows == 0) return {};
  std::vector<float> blob(rows * cols);
  std::memcpy(blob.data(), statement.Blob(2), num_bytes);
  return KeypointsFromBlob(blob.data(), rows, cols, path_, image_id);
}

FeatureDescriptors Database::ReadDescriptors(image_t image_id) const {
  Statement statement(db_, path_, "SELECT rows, cols, data FROM descriptors WHERE image_id=?;");
  statement.BindInt64(1, image_id);
  if (!statement.Step()) return FeatureDescriptors(0, 128);
  const Eigen::Index rows = statement.Int64(0);
  const Eigen::Index cols = statement.Int64(1);
  const size_t num_bytes = statement.NumBytes(2);
  if (rows < 0 || cols < 0 || num_bytes != static_cast<size_t>(rows * cols)) {
    throw InputError(path_.string() + ": descriptors of image " + std::to_string(image_id) +
                     ": blob of " + std::to_string(num_bytes) + " bytes for " +
                     std::to_string(rows) + "x" + std::to_string(cols) + " uint8");
  }
  FeatureDescriptors descriptors(rows, cols);
  if (num_bytes > 0) std::memcpy(descriptors.data(), statement.Blob(2), num_bytes);
  return descriptors;
}

size_t Database::NumKeypoints(image_t image_id) const {
  Statement statement(db_, path_, "SELECT rows FROM keypoints WHERE image_id=?;");
  statement.BindInt64(1, image_id);
  return statement.Step() ? static_cast<size_t>(statement.Int64(0)) : 0;
}

// ----- Matches ------------------------------------------------------------------------------

void Database::WriteMatches(image_t image_id1, image_t image_id2, const FeatureMatches& matches) {
  PARALLAX_CHECK_NE(image_id1, image_id2);
  const std::vector<uint32_t> blob = MatchesToBlob(matches, SwapImagePair(image_id1, image_id2));
  Statement statement(db_, path_,
                      "INSERT INTO matches(pair_id, rows, cols, data) VALUES(?, ?, ?, ?);");
  statement.BindInt64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  statement.BindInt64(2, static_cast<int64_t>(matches.size()));
  statement.BindInt64(3, 2);
  statement.BindBlob(4, blob.data(), blob.size() * sizeof(uint32_t));
  statement.Step(("cannot write matches of pair (" + std::to_string(image_id1) + ", " +
                  std::to_string(image_id2) + ")")
                     .c_str());
}

bool Database::ExistsMatches(image_t image_id1, image_t image_id2) const {
  Statement statement(db_, path_, "SELECT 1 FROM matches WHERE pair_id=?;");
  statement.BindInt64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  return statement.Step();
}

FeatureMatches Database::ReadMatches(image_t image_id1, image_t image_id2) const {
  Statement statement(db_, path_, "SELECT rows, cols, data FROM matches WHERE pair_id=?;");
  statement.BindInt64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  if (!statement.Step()) return {};
  return MatchesFromRow(statement, 0, SwapImagePair(image_id1, image_id2), path_);
}

std::vector<std::pair<image_pair_t, FeatureMatches>> Database::ReadAllMatches() const {
  Statement statement(db_, path_,
                      "SELECT pair_id, rows, cols, data FROM matches ORDER BY pair_id;");
  std::vector<std::pair<image_pair_t, FeatureMatches>> all_matches;
  while (statement.Step()) {
    all_matches.emplace_back(static_cast<image_pair_t>(statement.Int64(0)),
                             MatchesFromRow(statement, 1, false, path_));
  }
  return all_matches;
}

// ----- Two-view geometries ------------------------------------------------------------------

void Database::DeleteTwoViewGeometry(image_t image_id1, image_t image_id2) {
  Statement statement(db_, path_, "DELETE FROM two_view_geometries WHERE pair_id = ?;");
  statement.BindInt64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  statement.Step("cannot delete a two-view geometry");
}

void Database::WriteTwoViewGeometry(image_t image_id1, image_t image_id2,
                                    const TwoViewGeometry& geometry) {
  PARALLAX_CHECK_NE(image_id1, image_id2);
  const TwoViewGeometry stored =
      SwapImagePair(image_id1, image_id2) ? InvertTwoViewGeometry(geometry) : geometry;
  const std::vector<uint32_t> blob = MatchesToBlob(stored.inlier_matches, false);
  // Row-major 3x3 blobs, as COLMAP transposes its column-major Eigen matrices before writing.
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> F = stored.F;
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> E = stored.E;
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> H = stored.H;
  const Eigen::Vector4d qvec(stored.cam2_from_cam1.rotation.w(), stored.cam2_from_cam1.rotation.x(),
                             stored.cam2_from_cam1.rotation.y(),
                             stored.cam2_from_cam1.rotation.z());
  const Eigen::Vector3d tvec = stored.cam2_from_cam1.translation;

  Statement statement(db_, path_,
                      "INSERT INTO two_view_geometries(pair_id, rows, cols, data, config, F, E, "
                      "H, qvec, tvec) VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?, ?);");
  statement.BindInt64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  statement.BindInt64(2, static_cast<int64_t>(stored.inlier_matches.size()));
  statement.BindInt64(3, 2);
  statement.BindBlob(4, blob.data(), blob.size() * sizeof(uint32_t));
  statement.BindInt64(5, stored.config);
  // COLMAP stores the matrices and pose only for pairs with inliers (empty blobs otherwise).
  const bool has_inliers = !stored.inlier_matches.empty();
  statement.BindBlob(6, F.data(), has_inliers ? 9 * sizeof(double) : 0);
  statement.BindBlob(7, E.data(), has_inliers ? 9 * sizeof(double) : 0);
  statement.BindBlob(8, H.data(), has_inliers ? 9 * sizeof(double) : 0);
  statement.BindBlob(9, qvec.data(), has_inliers ? 4 * sizeof(double) : 0);
  statement.BindBlob(10, tvec.data(), has_inliers ? 3 * sizeof(double) : 0);
  statement.Step(("cannot write two-view geometry of pair (" + std::to_string(image_id1) + ", " +
                  std::to_string(image_id2) + ")")
                     .c_str());
}

bool Database::ExistsTwoViewGeometry(image_t image_id1, image_t image_id2) const {
  Statement statement(db_, path_, "SELECT 1 FROM two_view_geometries WHERE pair_id=?;");
  statement.BindInt64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  return statement.Step();
}

TwoViewGeometry Database::ReadTwoViewGeometry(image_t image_id1, image_t image_id2) const {
  Statement statement(db_, path_,
                      "SELECT rows, cols, data, config, F, E, H, qvec, tvec "
                      "FROM two_view_geometries WHERE pair_id=?;");
  statement.BindInt64(1, static_cast<int64_t>(ImagePairToPairId(image_id1, image_id2)));
  if (!statement.Step()) return TwoViewGeometry();
  const TwoViewGeometry geometry = TwoViewGeometryFromRow(statement, 0, path_);
  return SwapImagePair(image_id1, image_id2) ? InvertTwoViewGeometry(geometry) : geometry;
}

std::vector<std::pair<image_pair_t, TwoViewGeometry>> Database::ReadTwoViewGeometries() const {
  Statement statement(db_, path_,
                      "SELECT pair_id, rows, cols, data, config, F, E, H, qvec, tvec "
                      "FROM two_view_geometries ORDER BY pair_id;");
  std::vector<std::pair<image_pair_t, TwoViewGeometry>> geometries;
  while (statement.Step()) {
    geometries.emplace_back(static_cast<image_pair_t>(statement.Int64(0)),
                            TwoViewGeometryFromRow(statement, 1, path_));
  }
  return geometries;
}

std::vector<std::pair<image_pair_t, int>> Database::ReadTwoViewGeometryNumInliers() const {
  Statement statement(db_, path_,
                      "SELECT pair_id, rows FROM two_view_geometries "
                      "WHERE rows > 0 AND config NOT IN (0, 1) ORDER BY pair_id;");
  std::vector<std::pair<image_pair_t, int>> num_inliers;
  while (statement.Step()) {
    num_inliers.emplace_back(static_cast<image_pair_t>(statement.Int64(0)),
                             static_cast<int>(statement.Int64(1)));
  }
  return num_inliers;
}

// ----- Counts -------------------------------------------------------------------------------

namespace {
size_t CountRows(sqlite3* db, const std::filesystem::path& path, const char* sql) {
  Statement statement(db, path, sql);
  return statement.Step() ? static_cast<size_t>(statement.Int64(0)) : 0;
}
}  // namespace

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
