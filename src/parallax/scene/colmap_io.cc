#include "parallax/scene/colmap_io.h"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <istream>
#include <limits>
#include <ostream>
#include <string>
#include <string_view>
#include <type_traits>

#include "parallax/util/byte_order.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"

namespace parallax {
namespace {

// ------------------------------------------------------------------------------------------
// Error context shared by the text and binary readers.

// Reads a text stream line by line, tracking the line number for error messages.
class LineReader {
 public:
  LineReader(std::istream& stream, const std::string& source) : stream_(stream), source_(source) {}

  // The next line, trimmed (Windows line endings and trailing spaces removed); false at end.
  bool NextLine(std::string_view* line) {
    if (!std::getline(stream_, line_)) return false;
    ++line_number_;
    const char* whitespace = " \t\r\n\f\v";
    const size_t first = line_.find_first_not_of(whitespace);
    if (first == std::string::npos) {
      *line = std::string_view();
    } else {
      const size_t last = line_.find_last_not_of(whitespace);
      *line = std::string_view(line_).substr(first, last - first + 1);
    }
    return true;
  }

  // The next line that is neither empty nor a '#' comment; false at end.
  bool NextDataLine(std::string_view* line) {
    while (NextLine(line)) {
      if (!line->empty() && line->front() != '#') return true;
    }
    return false;
  }

  [[noreturn]] void Fail(const std::string& reason) const {
    throw InputError(source_ + ":" + std::to_string(line_number_) + ": " + reason);
  }

 private:
  std::istream& stream_;
  const std::string& source_;
  std::string line_;
  size_t line_number_ = 0;
};

// Splits one line into whitespace-separated tokens without copying.
class Tokenizer {
 public:
  explicit Tokenizer(std::string_view text) : text_(text) {}

  bool Next(std::string_view* token) {
    SkipWhitespace();
    if (position_ >= text_.size()) return false;
    const size_t begin = position_;
    while (position_ < text_.size() && !IsWhitespace(text_[position_])) ++position_;
    *token = text_.substr(begin, position_ - begin);
    return true;
  }

  // Everything after the current token, trimmed (image names may contain spaces).
  std::string_view Rest() {
    SkipWhitespace();
    return text_.substr(position_);
  }

  size_t CountRemaining() const {
    Tokenizer copy = *this;
    size_t count = 0;
    std::string_view token;
    while (copy.Next(&token)) ++count;
    return count;
  }

 private:
  static bool IsWhitespace(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
  }
  void SkipWhitespace() {
    while (position_ < text_.size() && IsWhitespace(text_[position_])) ++position_;
  }

  std::string_view text_;
  size_t position_ = 0;
};

template <typename T>
T ParseToken(std::string_view token, const LineReader& reader, const char* what) {
  T value{};
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (error != std::errc() || end != token.data() + token.size()) {
    reader.Fail("invalid " + std::string(what) + " '" + std::string(token) + "'");
  }
  return value;
}

template <typename T>
T NextToken(Tokenizer* tokenizer, const LineReader& reader, const char* what) {
  std::string_view token;
  if (!tokenizer->Next(&token)) reader.Fail("missing " + std::string(what));
  return ParseToken<T>(token, reader, what);
}

// Reads little-endian values, keeping count of the bytes left so that a corrupt count fails
// before it can drive a huge allocation.
class BinaryReader {
 public:
  BinaryReader(std::istream& stream, const std::string& source) : stream_(stream), source_(source) {
    const std::istream::pos_type begin = stream_.tellg();
    if (begin != std::istream::pos_type(-1)) {
      stream_.seekg(0, std::ios::end);
      const std::istream::pos_type end = stream_.tellg();
      stream_.seekg(begin);
      if (end != std::istream::pos_type(-1) && stream_) {
        remaining_ = static_cast<uint64_t>(end - begin);
        size_known_ = true;
      }
    }
    stream_.clear();
  }

  template <typename T>
  T Read(const char* what) {
    static_assert(std::is_arithmetic_v<T>);
    char bytes[sizeof(T)];
    if (!stream_.read(bytes, sizeof(T))) Fail("truncated: cannot read " + std::string(what));
    Consume(sizeof(T));
    if constexpr (std::endian::native == std::endian::big) std::reverse(bytes, bytes + sizeof(T));
    T value;
    std::memcpy(&value, bytes, sizeof(T));
    return value;
  }

  // Whether counts are bounded by the stream size (else nothing may be reserved from them).
  bool SizeKnown() const { return size_known_; }

  // A count of records of at least `min_record_bytes` each that must fit in the stream.
  uint64_t ReadCount(size_t min_record_bytes, const char* what) {
    const uint64_t count = Read<uint64_t>(what);
    if (size_known_ && count > remaining_ / min_record_bytes) {
      Fail(std::string(what) + " " + std::to_string(count) + " exceeds what the remaining " +
           std::to_string(remaining_) + " bytes can hold");
    }
    return count;
  }

  std::string ReadNullTerminated(const char* what) {
    constexpr size_t kMaxLength = 1 << 16;
    std::string text;
    for (;;) {
      const int c = stream_.get();
      if (c == std::char_traits<char>::eof()) Fail("truncated: unterminated " + std::string(what));
      Consume(1);
      if (c == '\0') return text;
      if (text.size() >= kMaxLength) Fail(std::string(what) + " longer than 65536 bytes");
      text.push_back(static_cast<char>(c));
    }
  }

  [[noreturn]] void Fail(const std::string& reason) const {
    throw InputError(source_ + ":byte " + std::to_string(offset_) + ": " + reason);
  }

 private:
  void Consume(size_t bytes) {
    offset_ += bytes;
    remaining_ = remaining_ >= bytes ? remaining_ - bytes : 0;
  }

  std::istream& stream_;
  const std::string& source_;
  uint64_t offset_ = 0;
  // Unknown for streams that cannot seek: then counts are not bounded up front, and a lying
  // count runs into the end of the stream after allocating no more than the stream held.
  bool size_known_ = false;
  uint64_t remaining_ = 0;
};

// A double as a stream with max_digits10 precision writes it (printf's %.17g, COLMAP's text
// models' form), through std::to_chars: the same bytes about ten times faster than the
// stream's own formatting, which took most of the time of writing a text model.
struct Digits17 {
  double value;
};

std::ostream& operator<<(std::ostream& stream, Digits17 number) {
  std::array<char, 32> buffer;
  const auto result =
      std::to_chars(buffer.data(), buffer.data() + buffer.size(), number.value,
                    std::chars_format::general, std::numeric_limits<double>::max_digits10);
  return stream.write(buffer.data(), result.ptr - buffer.data());
}

// Restores a stream's formatting when the writer returns.
class PrecisionGuard {
 public:
  explicit PrecisionGuard(std::ostream& stream)
      : stream_(stream), flags_(stream.flags()), precision_(stream.precision()) {
    stream_.flags(std::ios::dec);
    // Round-trip precision, as COLMAP writes its text models.
    stream_.precision(std::numeric_limits<double>::max_digits10);
  }
  ~PrecisionGuard() {
    stream_.flags(flags_);
    stream_.precision(precision_);
  }

 private:
  std::ostream& stream_;
  std::ios::fmtflags flags_;
  std::streamsize precision_;
};

// ------------------------------------------------------------------------------------------
// Validation shared by both formats: everything that Reconstruction would reject with a
// CheckError becomes an InputError naming the source position.

template <typename Context>
void AddCameraChecked(const Context& context, Camera camera, Reconstruction* reconstruction) {
  if (camera.camera_id == kInvalidCameraId) context.Fail("invalid camera id");
  if (reconstruction->ExistsCamera(camera.camera_id)) {
    context.Fail("duplicate camera id " + std::to_string(camera.camera_id));
  }
  if (!camera.VerifyParams()) {
    context.Fail("invalid parameters for camera " + std::to_string(camera.camera_id));
  }
  reconstruction->AddCamera(std::move(camera));
}

// Checks an image's first record (before its keypoints, so that errors point at it).
template <typename Context>
void CheckImageHeader(const Context& context, const Image& image,
                      const Reconstruction& reconstruction) {
  if (image.image_id == kInvalidImageId) context.Fail("invalid image id");
  if (reconstruction.ExistsImage(image.image_id)) {
    context.Fail("duplicate image id " + std::to_string(image.image_id));
  }
  if (!reconstruction.ExistsCamera(image.camera_id)) {
    context.Fail("image " + std::to_string(image.image_id) + " refers to missing camera " +
                 std::to_string(image.camera_id));
  }
  const Eigen::Quaterniond& rotation = image.cam_from_world.rotation;
  if (!rotation.coeffs().allFinite() || rotation.norm() < 1e-6 ||
      !image.cam_from_world.translation.allFinite()) {
    context.Fail("invalid pose of image " + std::to_string(image.image_id));
  }
  if (image.name.empty()) context.Fail("image " + std::to_string(image.image_id) + " has no name");
}

// Observations are linked by the points' tracks (read next); a model's images are registered.
void AddModelImage(Image image, Reconstruction* reconstruction) {
  for (Point2D& point2D : image.points2D) point2D.point3D_id = kInvalidPoint3DId;
  image.registered = true;
  reconstruction->AddImage(std::move(image));
}

template <typename Context>
void AddPoint3DChecked(const Context& context, point3D_t point3D_id, Point3D point,
                       Reconstruction* reconstruction) {
  if (point3D_id == kInvalidPoint3DId) context.Fail("invalid 3D point id");
  if (reconstruction->ExistsPoint3D(point3D_id)) {
    context.Fail("duplicate 3D point id " + std::to_string(point3D_id));
  }
  if (!point.xyz.allFinite()) {
    context.Fail("invalid position of 3D point " + std::to_string(point3D_id));
  }
  for (size_t i = 0; i < point.track.elements.size(); ++i) {
    const TrackElement& element = point.track.elements[i];
    if (!reconstruction->ExistsImage(element.image_id)) {
      context.Fail("3D point " + std::to_string(point3D_id) + " observed in missing image " +
                   std::to_string(element.image_id));
    }
    const Image& image = reconstruction->GetImage(element.image_id);
    if (element.point2D_idx >= image.points2D.size()) {
      context.Fail("3D point " + std::to_string(point3D_id) + " refers to missing keypoint " +
                   std::to_string(element.point2D_idx) + " of image " +
                   std::to_string(element.image_id));
    }
    const Point2D& point2D = image.points2D[element.point2D_idx];
    const bool repeated = std::find(point.track.elements.begin(), point.track.elements.begin() + i,
                                    element) != point.track.elements.begin() + i;
    if (point2D.HasPoint3D() || repeated) {
      context.Fail("keypoint " + std::to_string(element.point2D_idx) + " of image " +
                   std::to_string(element.image_id) + " observes two 3D points");
    }
  }
  reconstruction->AddPoint3DWithId(point3D_id, std::move(point));
}

}  // namespace

// ------------------------------------------------------------------------------------------
// Text writers.

void WriteCamerasText(const Reconstruction& reconstruction, std::ostream& stream) {
  const PrecisionGuard guard(stream);
  stream << "# Camera list with one line of data per camera:\n"
         << "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
         << "# Number of cameras: " << reconstruction.NumCameras() << "\n";
  for (const auto& [camera_id, camera] : reconstruction.Cameras()) {
    stream << camera_id << " " << camera.ModelName() << " " << camera.width << " " << camera.height;
    for (const double param : camera.params) stream << " " << Digits17{param};
    stream << "\n";
  }
}

void WriteImagesText(const Reconstruction& reconstruction, std::ostream& stream) {
  const PrecisionGuard guard(stream);
  stream << "# Image list with two lines of data per image:\n"
         << "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
         << "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
         << "# Number of images: " << reconstruction.NumRegImages()
         << ", mean observations per image: " << reconstruction.ComputeMeanObservationsPerRegImage()
         << "\n";
  for (const auto& [image_id, image] : reconstruction.Images()) {
    if (!image.registered) continue;
    const Eigen::Quaterniond& q = image.cam_from_world.rotation;
    const Eigen::Vector3d& t = image.cam_from_world.translation;
    stream << image_id << " " << Digits17{q.w()} << " " << Digits17{q.x()} << " " << Digits17{q.y()}
           << " " << Digits17{q.z()} << " " << Digits17{t.x()} << " " << Digits17{t.y()} << " "
           << Digits17{t.z()} << " " << image.camera_id << " " << image.name << "\n";
    bool first = true;
    for (const Point2D& point2D : image.points2D) {
      if (!first) stream << " ";
      first = false;
      stream << Digits17{point2D.xy.x()} << " " << Digits17{point2D.xy.y()} << " ";
      if (point2D.HasPoint3D()) {
        stream << point2D.point3D_id;
      } else {
        stream << -1;
      }
    }
    stream << "\n";
  }
}

void WritePoints3DText(const Reconstruction& reconstruction, std::ostream& stream) {
  const PrecisionGuard guard(stream);
  stream << "# 3D point list with one line of data per point:\n"
         << "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
         << "# Number of points: " << reconstruction.NumPoints3D()
         << ", mean track length: " << reconstruction.ComputeMeanTrackLength() << "\n";
  for (const auto& [point3D_id, point] : reconstruction.Points3D()) {
    stream << point3D_id << " " << Digits17{point.xyz.x()} << " " << Digits17{point.xyz.y()} << " "
           << Digits17{point.xyz.z()} << " " << static_cast<int>(point.color[0]) << " "
           << static_cast<int>(point.color[1]) << " " << static_cast<int>(point.color[2]) << " "
           << Digits17{point.error};
    for (const TrackElement& element : point.track.elements) {
      stream << " " << element.image_id << " " << element.point2D_idx;
    }
    stream << "\n";
  }
}

// COLMAP 4's rigs and frames, for a model without rigs: one rig per camera (its id, the camera
// its only sensor) and one frame per registered image (its id, the image its only data), the
// rig's pose the camera's. COLMAP 4 writes them beside every model; 3.x ignores them.
constexpr int32_t kCameraSensorType = 0;  // COLMAP's SensorType::CAMERA.

void WriteRigsText(const Reconstruction& reconstruction, std::ostream& stream) {
  stream << "# Rig calib list with one line of data per calib:\n"
         << "#   RIG_ID, NUM_SENSORS, REF_SENSOR_TYPE, REF_SENSOR_ID, SENSORS[] as (SENSOR_TYPE, "
            "SENSOR_ID, HAS_POSE, [QW, QX, QY, QZ, TX, TY, TZ])\n"
         << "# Number of rigs: " << reconstruction.NumCameras() << "\n";
  for (const auto& [camera_id, camera] : reconstruction.Cameras()) {
    stream << camera_id << " 1 CAMERA " << camera_id << "\n";
  }
}

void WriteFramesText(const Reconstruction& reconstruction, std::ostream& stream) {
  const PrecisionGuard guard(stream);
  stream << "# Frame list with one line of data per frame:\n"
         << "#   FRAME_ID, RIG_ID, RIG_FROM_WORLD[QW, QX, QY, QZ, TX, TY, TZ], NUM_DATA_IDS, "
            "DATA_IDS[] as (SENSOR_TYPE, SENSOR_ID, DATA_ID)\n"
         << "# Number of frames: " << reconstruction.NumRegImages() << "\n";
  for (const auto& [image_id, image] : reconstruction.Images()) {
    if (!image.registered) continue;
    const Eigen::Quaterniond& q = image.cam_from_world.rotation;
    const Eigen::Vector3d& t = image.cam_from_world.translation;
    stream << image_id << " " << image.camera_id << " " << Digits17{q.w()} << " " << Digits17{q.x()}
           << " " << Digits17{q.y()} << " " << Digits17{q.z()} << " " << Digits17{t.x()} << " "
           << Digits17{t.y()} << " " << Digits17{t.z()} << " 1 CAMERA " << image.camera_id << " "
           << image_id << "\n";
  }
}

// ------------------------------------------------------------------------------------------
// Binary writers.

void WriteCamerasBinary(const Reconstruction& reconstruction, std::ostream& stream) {
  WriteBinary<uint64_t>(stream, reconstruction.NumCameras());
  for (const auto& [camera_id, camera] : reconstruction.Cameras()) {
    WriteBinary<uint32_t>(stream, camera_id);
    WriteBinary<int32_t>(stream, static_cast<int32_t>(camera.model_id));
    WriteBinary<uint64_t>(stream, camera.width);
    WriteBinary<uint64_t>(stream, camera.height);
    for (const double param : camera.params) WriteBinary<double>(stream, param);
  }
}

void WriteImagesBinary(const Reconstruction& reconstruction, std::ostream& stream) {
  WriteBinary<uint64_t>(stream, reconstruction.NumRegImages());
  for (const auto& [image_id, image] : reconstruction.Images()) {
    if (!image.registered) continue;
    WriteBinary<uint32_t>(stream, image_id);
    const Eigen::Quaterniond& q = image.cam_from_world.rotation;
    for (const double value : {q.w(), q.x(), q.y(), q.z()}) WriteBinary<double>(stream, value);
    for (int c = 0; c < 3; ++c) WriteBinary<double>(stream, image.cam_from_world.translation[c]);
    WriteBinary<uint32_t>(stream, image.camera_id);
    stream.write(image.name.c_str(), static_cast<std::streamsize>(image.name.size() + 1));
    WriteBinary<uint64_t>(stream, image.points2D.size());
    for (const Point2D& point2D : image.points2D) {
      WriteBinary<double>(stream, point2D.xy.x());
      WriteBinary<double>(stream, point2D.xy.y());
      WriteBinary<uint64_t>(stream, point2D.point3D_id);  // kInvalidPoint3DId is uint64 max.
    }
  }
}

void WriteRigsBinary(const Reconstruction& reconstruction, std::ostream& stream) {
  WriteBinary<uint64_t>(stream, reconstruction.NumCameras());
  for (const auto& [camera_id, camera] : reconstruction.Cameras()) {
    WriteBinary<uint32_t>(stream, camera_id);  // Rig id.
    WriteBinary<uint32_t>(stream, 1);          // Sensors: the reference one only.
    WriteBinary<int32_t>(stream, kCameraSensorType);
    WriteBinary<uint32_t>(stream, camera_id);
  }
}

void WriteFramesBinary(const Reconstruction& reconstruction, std::ostream& stream) {
  WriteBinary<uint64_t>(stream, reconstruction.NumRegImages());
  for (const auto& [image_id, image] : reconstruction.Images()) {
    if (!image.registered) continue;
    WriteBinary<uint32_t>(stream, image_id);         // Frame id.
    WriteBinary<uint32_t>(stream, image.camera_id);  // Rig id.
    const Eigen::Quaterniond& q = image.cam_from_world.rotation;
    for (const double value : {q.w(), q.x(), q.y(), q.z()}) WriteBinary<double>(stream, value);
    for (int c = 0; c < 3; ++c) WriteBinary<double>(stream, image.cam_from_world.translation[c]);
    WriteBinary<uint32_t>(stream, 1);  // Data ids: the image.
    WriteBinary<int32_t>(stream, kCameraSensorType);
    WriteBinary<uint32_t>(stream, image.camera_id);
    WriteBinary<uint64_t>(stream, image_id);
  }
}

void WritePoints3DBinary(const Reconstruction& reconstruction, std::ostream& stream) {
  WriteBinary<uint64_t>(stream, reconstruction.NumPoints3D());
  for (const auto& [point3D_id, point] : reconstruction.Points3D()) {
    WriteBinary<uint64_t>(stream, point3D_id);
    for (int c = 0; c < 3; ++c) WriteBinary<double>(stream, point.xyz[c]);
    for (int c = 0; c < 3; ++c) WriteBinary<uint8_t>(stream, point.color[c]);
    WriteBinary<double>(stream, point.error);
    WriteBinary<uint64_t>(stream, point.track.Length());
    for (const TrackElement& element : point.track.elements) {
      WriteBinary<uint32_t>(stream, element.image_id);
      WriteBinary<uint32_t>(stream, element.point2D_idx);
    }
  }
}

// ------------------------------------------------------------------------------------------
// Text readers.

void ReadCamerasText(std::istream& stream, const std::string& source,
                     Reconstruction* reconstruction) {
  PARALLAX_CHECK(reconstruction != nullptr);
  LineReader reader(stream, source);
  std::string_view line;
  while (reader.NextDataLine(&line)) {
    Tokenizer tokens(line);
    Camera camera;
    camera.camera_id = NextToken<camera_t>(&tokens, reader, "CAMERA_ID");
    std::string_view model_name;
    if (!tokens.Next(&model_name)) reader.Fail("missing MODEL");
    camera.model_id = CameraModelIdFromName(std::string(model_name));
    if (camera.model_id == CameraModelId::kInvalid) {
      reader.Fail("unknown camera model '" + std::string(model_name) + "'");
    }
    camera.width = NextToken<uint64_t>(&tokens, reader, "WIDTH");
    camera.height = NextToken<uint64_t>(&tokens, reader, "HEIGHT");
    const size_t num_params = tokens.CountRemaining();
    const int expected = CameraModelNumParams(camera.model_id);
    if (num_params != static_cast<size_t>(expected)) {
      reader.Fail(std::string(model_name) + " takes " + std::to_string(expected) +
                  " parameters, got " + std::to_string(num_params));
    }
    camera.params.resize(num_params);
    for (double& param : camera.params) param = NextToken<double>(&tokens, reader, "parameter");
    AddCameraChecked(reader, std::move(camera), reconstruction);
  }
  if (stream.bad()) reader.Fail("read failed");
}

void ReadImagesText(std::istream& stream, const std::string& source,
                    Reconstruction* reconstruction) {
  PARALLAX_CHECK(reconstruction != nullptr);
  LineReader reader(stream, source);
  std::string_view line;
  while (reader.NextDataLine(&line)) {
    Tokenizer tokens(line);
    Image image;
    image.image_id = NextToken<image_t>(&tokens, reader, "IMAGE_ID");
    double q[4];
    for (double& value : q) value = NextToken<double>(&tokens, reader, "quaternion coordinate");
    image.cam_from_world.rotation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
    for (int c = 0; c < 3; ++c) {
      image.cam_from_world.translation[c] = NextToken<double>(&tokens, reader, "translation");
    }
    image.camera_id = NextToken<camera_t>(&tokens, reader, "CAMERA_ID");
    image.name = std::string(tokens.Rest());
    if (image.name.empty()) reader.Fail("missing NAME");
    CheckImageHeader(reader, image, *reconstruction);
    // The second line of the pair (possibly empty; a missing last line means no keypoints).
    std::string_view points_line;
    if (reader.NextLine(&points_line)) {
      if (!points_line.empty() && points_line.front() == '#') {
        reader.Fail("expected the POINTS2D line of image " + std::to_string(image.image_id));
      }
      Tokenizer point_tokens(points_line);
      const size_t num_tokens = point_tokens.CountRemaining();
      if (num_tokens % 3 != 0) {
        reader.Fail("POINTS2D needs X Y POINT3D_ID triplets, got " + std::to_string(num_tokens) +
                    " values");
      }
      image.points2D.resize(num_tokens / 3);
      for (Point2D& point2D : image.points2D) {
        point2D.xy.x() = NextToken<double>(&point_tokens, reader, "keypoint X");
        point2D.xy.y() = NextToken<double>(&point_tokens, reader, "keypoint Y");
        if (!point2D.xy.allFinite()) reader.Fail("non-finite keypoint");
        std::string_view id_token;
        point_tokens.Next(&id_token);
        // Validated, but the links come from the points' tracks.
        if (id_token != "-1") ParseToken<point3D_t>(id_token, reader, "POINT3D_ID");
      }
    }
    AddModelImage(std::move(image), reconstruction);
  }
  if (stream.bad()) reader.Fail("read failed");
}

void ReadPoints3DText(std::istream& stream, const std::string& source,
                      Reconstruction* reconstruction) {
  PARALLAX_CHECK(reconstruction != nullptr);
  LineReader reader(stream, source);
  std::string_view line;
  while (reader.NextDataLine(&line)) {
    Tokenizer tokens(line);
    const point3D_t point3D_id = NextToken<point3D_t>(&tokens, reader, "POINT3D_ID");
    Point3D point;
    for (int c = 0; c < 3; ++c) point.xyz[c] = NextToken<double>(&tokens, reader, "coordinate");
    for (int c = 0; c < 3; ++c) {
      const unsigned value = NextToken<unsigned>(&tokens, reader, "colour");
      if (value > 255) reader.Fail("colour " + std::to_string(value) + " out of 0..255");
      point.color[c] = static_cast<uint8_t>(value);
    }
    point.error = NextToken<double>(&tokens, reader, "ERROR");
    const size_t num_tokens = tokens.CountRemaining();
    if (num_tokens % 2 != 0) reader.Fail("TRACK needs IMAGE_ID POINT2D_IDX pairs");
    point.track.elements.resize(num_tokens / 2);
    for (TrackElement& element : point.track.elements) {
      element.image_id = NextToken<image_t>(&tokens, reader, "track IMAGE_ID");
      element.point2D_idx = NextToken<point2D_t>(&tokens, reader, "track POINT2D_IDX");
    }
    AddPoint3DChecked(reader, point3D_id, std::move(point), reconstruction);
  }
  if (stream.bad()) reader.Fail("read failed");
}

// ------------------------------------------------------------------------------------------
// Binary readers. Minimum record sizes bound the counts by the bytes left.

void ReadCamerasBinary(std::istream& stream, const std::string& source,
                       Reconstruction* reconstruction) {
  PARALLAX_CHECK(reconstruction != nullptr);
  BinaryReader reader(stream, source);
  const uint64_t num_cameras = reader.ReadCount(4 + 4 + 8 + 8, "number of cameras");
  for (uint64_t i = 0; i < num_cameras; ++i) {
    Camera camera;
    camera.camera_id = reader.Read<uint32_t>("camera_id");
    const int32_t model_id = reader.Read<int32_t>("model_id");
    if (!ExistsCameraModel(model_id))
      reader.Fail("unknown camera model id " + std::to_string(model_id));
    camera.model_id = static_cast<CameraModelId>(model_id);
    camera.width = reader.Read<uint64_t>("width");
    camera.height = reader.Read<uint64_t>("height");
    camera.params.resize(CameraModelNumParams(camera.model_id));
    for (double& param : camera.params) param = reader.Read<double>("camera parameter");
    AddCameraChecked(reader, std::move(camera), reconstruction);
  }
}

void ReadImagesBinary(std::istream& stream, const std::string& source,
                      Reconstruction* reconstruction) {
  PARALLAX_CHECK(reconstruction != nullptr);
  BinaryReader reader(stream, source);
  const uint64_t num_images = reader.ReadCount(4 + 7 * 8 + 4 + 1 + 8, "number of images");
  for (uint64_t i = 0; i < num_images; ++i) {
    Image image;
    image.image_id = reader.Read<uint32_t>("image_id");
    double q[4];
    for (double& value : q) value = reader.Read<double>("quaternion");
    image.cam_from_world.rotation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
    for (int c = 0; c < 3; ++c)
      image.cam_from_world.translation[c] = reader.Read<double>("translation");
    image.camera_id = reader.Read<uint32_t>("camera_id");
    image.name = reader.ReadNullTerminated("image name");
    CheckImageHeader(reader, image, *reconstruction);
    const uint64_t num_points2D = reader.ReadCount(3 * 8, "number of keypoints");
    if (reader.SizeKnown()) image.points2D.reserve(num_points2D);
    for (uint64_t idx = 0; idx < num_points2D; ++idx) {
      Point2D point2D;
      point2D.xy.x() = reader.Read<double>("keypoint x");
      point2D.xy.y() = reader.Read<double>("keypoint y");
      if (!point2D.xy.allFinite()) reader.Fail("non-finite keypoint");
      reader.Read<uint64_t>("point3D_id");  // The links come from the points' tracks.
      image.points2D.push_back(point2D);
    }
    AddModelImage(std::move(image), reconstruction);
  }
}

void ReadPoints3DBinary(std::istream& stream, const std::string& source,
                        Reconstruction* reconstruction) {
  PARALLAX_CHECK(reconstruction != nullptr);
  BinaryReader reader(stream, source);
  const uint64_t num_points = reader.ReadCount(8 + 3 * 8 + 3 + 8 + 8, "number of 3D points");
  for (uint64_t i = 0; i < num_points; ++i) {
    const point3D_t point3D_id = reader.Read<uint64_t>("point3D_id");
    Point3D point;
    for (int c = 0; c < 3; ++c) point.xyz[c] = reader.Read<double>("coordinate");
    for (int c = 0; c < 3; ++c) point.color[c] = reader.Read<uint8_t>("colour");
    point.error = reader.Read<double>("error");
    const uint64_t track_length = reader.ReadCount(4 + 4, "track length");
    if (reader.SizeKnown()) point.track.elements.reserve(track_length);
    for (uint64_t k = 0; k < track_length; ++k) {
      TrackElement element;
      element.image_id = reader.Read<uint32_t>("track image_id");
      element.point2D_idx = reader.Read<uint32_t>("track point2D_idx");
      point.track.elements.push_back(element);
    }
    AddPoint3DChecked(reader, point3D_id, std::move(point), reconstruction);
  }
}

// ------------------------------------------------------------------------------------------
// Folders and files.

namespace {

template <typename ReadFunction>
void ReadFile(const std::filesystem::path& path, ReadFunction read,
              Reconstruction* reconstruction) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) ThrowCannotOpenForReading(path);
  read(stream, path.string(), reconstruction);
}

}  // namespace

void WriteReconstructionText(const Reconstruction& reconstruction,
                             const std::filesystem::path& dir) {
  CreateDirectoryOrThrow(dir);
  WriteFileAtomically(dir / "cameras.txt",
                      [&](std::ostream& stream) { WriteCamerasText(reconstruction, stream); });
  WriteFileAtomically(dir / "images.txt",
                      [&](std::ostream& stream) { WriteImagesText(reconstruction, stream); });
  WriteFileAtomically(dir / "points3D.txt",
                      [&](std::ostream& stream) { WritePoints3DText(reconstruction, stream); });
  WriteFileAtomically(dir / "rigs.txt",
                      [&](std::ostream& stream) { WriteRigsText(reconstruction, stream); });
  WriteFileAtomically(dir / "frames.txt",
                      [&](std::ostream& stream) { WriteFramesText(reconstruction, stream); });
}

void WriteReconstructionBinary(const Reconstruction& reconstruction,
                               const std::filesystem::path& dir) {
  CreateDirectoryOrThrow(dir);
  WriteFileAtomically(
      dir / "cameras.bin",
      [&](std::ostream& stream) { WriteCamerasBinary(reconstruction, stream); }, true);
  WriteFileAtomically(
      dir / "images.bin", [&](std::ostream& stream) { WriteImagesBinary(reconstruction, stream); },
      true);
  WriteFileAtomically(
      dir / "points3D.bin",
      [&](std::ostream& stream) { WritePoints3DBinary(reconstruction, stream); }, true);
  WriteFileAtomically(
      dir / "rigs.bin", [&](std::ostream& stream) { WriteRigsBinary(reconstruction, stream); },
      true);
  WriteFileAtomically(
      dir / "frames.bin", [&](std::ostream& stream) { WriteFramesBinary(reconstruction, stream); },
      true);
}

bool HasColmapModel(const std::filesystem::path& dir) {
  std::error_code error;
  return std::filesystem::exists(dir / "cameras.bin", error) ||
         std::filesystem::exists(dir / "cameras.txt", error);
}

Reconstruction ReadReconstruction(const std::filesystem::path& dir) {
  Reconstruction reconstruction;
  std::error_code error;
  if (!std::filesystem::exists(dir, error)) {
    throw MissingFileError(dir.string() + ": model folder does not exist");
  }
  if (std::filesystem::exists(dir / "cameras.bin", error)) {
    ReadFile(dir / "cameras.bin", ReadCamerasBinary, &reconstruction);
    ReadFile(dir / "images.bin", ReadImagesBinary, &reconstruction);
    ReadFile(dir / "points3D.bin", ReadPoints3DBinary, &reconstruction);
  } else if (std::filesystem::exists(dir / "cameras.txt", error)) {
    ReadFile(dir / "cameras.txt", ReadCamerasText, &reconstruction);
    ReadFile(dir / "images.txt", ReadImagesText, &reconstruction);
    ReadFile(dir / "points3D.txt", ReadPoints3DText, &reconstruction);
  } else {
    throw InputError(dir.string() + ": no COLMAP model here (neither cameras.bin nor cameras.txt)");
  }
  return reconstruction;
}

void WritePointsPly(const Reconstruction& reconstruction, const std::filesystem::path& path) {
  WriteFileAtomically(
      path,
      [&](std::ostream& stream) {
        stream << "ply\n"
               << "format binary_little_endian 1.0\n"
               << "element vertex " << reconstruction.NumPoints3D() << "\n"
               << "property float x\n"
               << "property float y\n"
               << "property float z\n"
               << "property uchar red\n"
               << "property uchar green\n"
               << "property uchar blue\n"
               << "end_header\n";
        for (const auto& [point3D_id, point] : reconstruction.Points3D()) {
          for (int c = 0; c < 3; ++c) WriteBinary<float>(stream, static_cast<float>(point.xyz[c]));
          for (int c = 0; c < 3; ++c) WriteBinary<uint8_t>(stream, point.color[c]);
        }
      },
      true);
}

}  // namespace parallax
