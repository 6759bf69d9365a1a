#include "kccd/calib/camera.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "kccd/file_reader.hpp"
#include "kccd/format_number.hpp"
#include "kccd/yaml_reader.hpp"

namespace kccd::calib {
namespace {

constexpr int kDistortionSizes[] = {4, 5, 8, 12, 14};
constexpr int kMaxMatrixSide = 16;  // rows, cols of a matrix in a camera file

[[noreturn]] void fail(const std::string& source, const std::string& field, const std::string& problem) {
  throw CameraError(InputLocation{source, 0, 0, field}, problem);
}

[[noreturn]] void failAt(const std::string& source, std::size_t line, const std::string& field,
                         const std::string& problem) {
  throw CameraError(InputLocation{source, line, 0, field}, problem);
}

// The whole file (a bounded regular file, never blocking on a FIFO or device), errors as CameraError.
std::string readCameraFile(const std::string& path) {
  try {
    return readRegularFile(path, kMaxCameraFileBytes, "camera file");
  } catch (const FileError& e) {
    throw CameraError(e.location(), e.problem());
  }
}

// Structure before YAML is parsed: text only, OpenCV's `%YAML:1.x` header, and document markers
// that OpenCV and YAML read alike. Returns the text with the header blanked (`%YAML:1.0` is not
// standard YAML), keeping the line numbers.
std::string checkCameraText(const std::string& text, const std::string& path) {
  std::size_t line = 1;
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '\n')
      ++line;
    else if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7f)
      failAt(path, line, "file", "control byte " + printable(std::string_view(&ch, 1)) + " (not a text file)");
  }
  // "---" or "..." at the start of a line with more text right after it is content to YAML but a
  // document marker to OpenCV: a file meaning two things to the two readers is refused.
  line = 1;
  for (std::size_t at = 0; at < text.size(); at = text.find('\n', at) + 1, ++line) {
    if (text.compare(at, 3, "---") != 0 && text.compare(at, 3, "...") != 0) {
      if (text.find('\n', at) == std::string::npos) break;
      continue;
    }
    const char next = at + 3 < text.size() ? text[at + 3] : '\n';
    if (next != '\n' && next != '\r' && next != ' ' && next != '\t')
      failAt(path, line, "document",
             "'" + text.substr(at, 3) + "' must stand alone at the start of a line (a document marker)");
    if (text.find('\n', at) == std::string::npos) break;
  }
  std::size_t start = 0;
  if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) start = 3;  // UTF-8 byte order mark
  const std::size_t eol = std::min(text.find('\n', start), text.size());
  std::string first = text.substr(start, eol - start);
  while (!first.empty() && (first.back() == '\r' || first.back() == ' ' || first.back() == '\t')) first.pop_back();
  const bool header = first.size() > 8 &&
                      (first.compare(0, 8, "%YAML:1.") == 0 || first.compare(0, 8, "%YAML 1.") == 0) &&
                      std::all_of(first.begin() + 8, first.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (text.find_first_not_of(" \t\r\n") == std::string::npos)
    fail(path, "file", "empty (an OpenCV YAML camera file starts with %YAML:1.0)");
  if (!header)
    failAt(path, 1, "header",
           "the first line must be %YAML:1.0 (an OpenCV FileStorage YAML camera file), not '" + printable(first, 40) +
               "'");
  std::string yaml = text;
  std::fill(yaml.begin(), yaml.begin() + static_cast<std::ptrdiff_t>(eol), ' ');
  return yaml;
}

// The camera file's nodes read by yaml-cpp (which streams a bounded document: no parser here can
// spin), each failure a CameraError at the node's line and column.
class CameraNodes {
 public:
  explicit CameraNodes(const std::string& path) : reader_(path, 40) {}

  YAML::Node load(const std::string& yaml) const { return reader_.load(yaml); }

  [[noreturn]] void failAtNode(const YAML::Node& node, const std::string& field, const std::string& problem) const {
    const InputLocation where = reader_.at(node, field);
    throw CameraError(where, problem);
  }

  // A plain scalar read as OpenCV reads numbers ("1.", ".5", "-1e-3", ".Inf", ".Nan"); nullopt
  // when it is no number.
  static std::optional<double> real(const YAML::Node& n) {
    if (!n.IsScalar() || n.Tag() != "?") return std::nullopt;  // quoted text is text
    std::string_view s = n.Scalar();
    const bool minus = !s.empty() && s.front() == '-';
    if (!s.empty() && (s.front() == '+' || s.front() == '-')) s.remove_prefix(1);
    if (s == ".inf" || s == ".Inf" || s == ".INF") return minus ? -HUGE_VAL : HUGE_VAL;
    if (s == ".nan" || s == ".NaN" || s == ".Nan" || s == ".NAN") return std::nan("");
    if (s.empty() || !(std::isdigit(static_cast<unsigned char>(s.front())) || s.front() == '.')) return std::nullopt;
    double v = 0.0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v, std::chars_format::general);
    if (end != s.data() + s.size() || (ec != std::errc() && ec != std::errc::result_out_of_range)) return std::nullopt;
    if (ec == std::errc::result_out_of_range) v = std::abs(v) < 1.0 ? 0.0 : HUGE_VAL;  // as strtod: 0 or inf
    return minus ? -v : v;
  }

  // A plain integer scalar ("640"), nullopt otherwise (also beyond int).
  static std::optional<long long> integer(const YAML::Node& n) {
    if (!n.IsScalar() || n.Tag() != "?") return std::nullopt;
    std::string_view s = n.Scalar();
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    long long v = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (s.empty() || end != s.data() + s.size() || ec != std::errc()) return std::nullopt;
    return v;
  }

  cv::Mat matrix(const YAML::Node& root, const char* field) const {
    const YAML::Node node = root[field];
    if (!node.IsDefined() || node.IsNull()) fail(reader_.source(), field, "missing");
    const std::string layout = "not an OpenCV matrix (!!opencv-matrix with rows, cols, dt, data)";
    if (!node.IsMap()) failAtNode(node, field, layout);
    const YAML::Node rows = node["rows"], cols = node["cols"], dt = node["dt"], data = node["data"];
    const std::optional<long long> r = integer(rows), c = integer(cols);
    if (!r || !c || !dt.IsScalar() || !data.IsSequence()) failAtNode(node, field, layout);
    if (*r < 1 || *r > kMaxMatrixSide || *c < 1 || *c > kMaxMatrixSide)
      failAtNode(node, field,
                 std::to_string(*r) + "x" + std::to_string(*c) + " is not a camera matrix size (rows and cols in 1.." +
                     std::to_string(kMaxMatrixSide) + ")");
    const std::string& type = dt.Scalar();
    if (type.size() != 1 || std::string("ucwsifd").find(type[0]) == std::string::npos)
      failAtNode(dt, field, "dt '" + printable(type, 20) + "' is not one of u, c, w, s, i, f, d");
    if (data.size() != static_cast<std::size_t>(*r * *c))
      failAtNode(data, field,
                 "data has " + std::to_string(data.size()) + " values, rows x cols is " + std::to_string(*r * *c));
    cv::Mat m(static_cast<int>(*r), static_cast<int>(*c), CV_64F);
    for (std::size_t i = 0; i < data.size(); ++i) {
      const std::optional<double> v = real(data[i]);
      if (!v) failAtNode(data[i], field, "data holds a value that is not a number");
      m.at<double>(static_cast<int>(i)) = asType(*v, type[0]);
    }
    return m;
  }

  int size(const YAML::Node& root, const char* field) const {
    const YAML::Node node = root[field];
    if (!node.IsDefined() || node.IsNull()) fail(reader_.source(), field, "missing");
    const std::optional<long long> v = integer(node);
    if (!v) failAtNode(node, field, "not an integer");
    if (*v <= 0 || *v > kMaxImageSide)
      failAtNode(node, field, std::to_string(*v) + " is not in 1.." + std::to_string(kMaxImageSide));
    return static_cast<int>(*v);
  }

  // An optional quality figure: absent, or a finite number >= 0.
  std::optional<double> quality(const YAML::Node& root, const char* field) const {
    const YAML::Node node = root[field];
    if (!node.IsDefined() || node.IsNull()) return std::nullopt;
    const std::optional<double> v = real(node);
    if (!v) failAtNode(node, field, "not a number");
    if (!std::isfinite(*v) || *v < 0.0) failAtNode(node, field, "must be a finite number >= 0");
    return v;
  }

  cv::Vec3d vec3(const YAML::Node& root, const char* field) const {
    const cv::Mat m = matrix(root, field);
    if (m.total() != 3) failAtNode(root[field], field, "needs 3 values, has " + std::to_string(m.total()));
    return {m.at<double>(0), m.at<double>(1), m.at<double>(2)};
  }

 private:
  // `v` stored as OpenCV stores a value of element type `dt` (rounded and saturated for integers).
  static double asType(double v, char dt) {
    switch (dt) {
      case 'u':
        return cv::saturate_cast<std::uint8_t>(v);
      case 'c':
        return cv::saturate_cast<std::int8_t>(v);
      case 'w':
        return cv::saturate_cast<std::uint16_t>(v);
      case 's':
        return cv::saturate_cast<std::int16_t>(v);
      case 'i':
        return cv::saturate_cast<int>(v);
      case 'f':
        return static_cast<double>(static_cast<float>(v));
      default:
        return v;
    }
  }

  YamlReader reader_;
};

}  // namespace

// Normalised coordinates of the pixel centres `pixels` (n x 1, CV_64FC2) through the inverse of
// the distortion model, and which of them the inversion really solved (checked by distorting
// again) within one image width / height of extra field on each side.
void undistortPixels(const Camera& camera, const cv::Mat& pixels, cv::Mat& normal, std::vector<unsigned char>& valid) {
  const int n = pixels.rows;
  const double fx = camera.camera_matrix(0, 0), fy = camera.camera_matrix(1, 1);
  const double cx = camera.camera_matrix(0, 2), cy = camera.camera_matrix(1, 2);
  cv::undistortPoints(pixels, normal, camera.camera_matrix, camera.distortion, cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-10));
  cv::Mat xyz(n, 1, CV_64FC3), back;
  for (int i = 0; i < n; ++i) {
    const cv::Vec2d p = normal.at<cv::Vec2d>(i);
    xyz.at<cv::Vec3d>(i) = cv::Vec3d(p[0], p[1], 1.0);
  }
  cv::projectPoints(xyz, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), camera.camera_matrix, camera.distortion, back);
  // At most one image width / height of extra field on each side.
  const double x_lo = -(cx + 0.5) / fx - camera.width / fx, x_hi = (camera.width - cx - 0.5) / fx + camera.width / fx;
  const double y_lo = -(cy + 0.5) / fy - camera.height / fy,
               y_hi = (camera.height - cy - 0.5) / fy + camera.height / fy;
  valid.assign(n, 0);
  for (int i = 0; i < n; ++i) {
    const cv::Vec2d& p = normal.at<cv::Vec2d>(i);
    const cv::Vec2d& b = back.at<cv::Vec2d>(i);
    const cv::Vec2d& u = pixels.at<cv::Vec2d>(i);
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || std::hypot(b[0] - u[0], b[1] - u[1]) > 1e-3) continue;
    if (p[0] < x_lo || p[0] > x_hi || p[1] < y_lo || p[1] > y_hi) continue;
    valid[i] = 1;
  }
}

bool Camera::distorted() const {
  return std::any_of(distortion.begin(), distortion.end(), [](double d) { return d != 0.0; });
}

Pose Camera::worldToCamera() const {
  cv::Matx33d r;
  cv::Rodrigues(rvec, r);
  Eigen::Matrix3d re;
  cv::cv2eigen(r, re);
  Pose p = Pose::Identity();
  p.linear() = re;
  p.translation() = Vec3(tvec[0], tvec[1], tvec[2]);
  return p;
}

void Camera::validate(const std::string& source) const {
  const std::string sides = "not in 1.." + std::to_string(kMaxImageSide);
  if (width <= 0 || width > kMaxImageSide) fail(source, "image_width", sides);
  if (height <= 0 || height > kMaxImageSide) fail(source, "image_height", sides);
  if (static_cast<long>(width) * height > kMaxImagePixels)
    fail(source, "image_width",
         std::to_string(width) + "x" + std::to_string(height) + " has more than " + std::to_string(kMaxImagePixels) +
             " pixels");
  const cv::Matx33d& k = camera_matrix;
  for (int i = 0; i < 9; ++i)
    if (!std::isfinite(k.val[i])) fail(source, "camera_matrix", "non-finite value");
  if (!(k(0, 0) > 0.0) || !(k(1, 1) > 0.0)) fail(source, "camera_matrix", "focal lengths fx, fy must be > 0");
  if (k(0, 1) != 0.0) fail(source, "camera_matrix", "skew (row 0, column 1) must be 0");
  if (k(1, 0) != 0.0 || k(2, 0) != 0.0 || k(2, 1) != 0.0 || k(2, 2) != 1.0)
    fail(source, "camera_matrix", "must have the form [fx 0 cx; 0 fy cy; 0 0 1]");
  if (k(0, 0) < 1.0 || k(0, 0) > kMaxFocal || k(1, 1) < 1.0 || k(1, 1) > kMaxFocal)
    fail(source, "camera_matrix",
         "focal lengths fx " + formatNumber(k(0, 0), 6) + ", fy " + formatNumber(k(1, 1), 6) + " must be in 1.." +
             formatNumber(kMaxFocal, 6) + " px");
  if (k(0, 2) < -width || k(0, 2) > 2.0 * width || k(1, 2) < -height || k(1, 2) > 2.0 * height)
    fail(source, "camera_matrix",
         "principal point (" + formatNumber(k(0, 2), 6) + ", " + formatNumber(k(1, 2), 6) +
             ") must lie within one image size of the image (cx in -width..2 width, cy in -height..2 height)");
  if (!std::count(std::begin(kDistortionSizes), std::end(kDistortionSizes), static_cast<int>(distortion.size())))
    fail(source, "distortion_coefficients", "needs 4, 5, 8, 12 or 14 values, has " + std::to_string(distortion.size()));
  for (std::size_t i = 0; i < distortion.size(); ++i) {
    if (!std::isfinite(distortion[i])) fail(source, "distortion_coefficients", "non-finite value");
    const double bound = i >= 12 ? 1.0 : kMaxDistortion;  // tilt angles tx, ty in radians
    if (std::abs(distortion[i]) > bound)
      fail(source, "distortion_coefficients",
           "coefficient " + std::to_string(i) + " = " + formatNumber(distortion[i], 6) +
               " is out of range (|k|, |p|, |s| <= " + formatNumber(kMaxDistortion, 6) + ", tilt |tx|, |ty| <= 1 rad)");
  }
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(rvec[i])) fail(source, "rvec", "non-finite value");
    if (!std::isfinite(tvec[i])) fail(source, "tvec", "non-finite value");
  }
  if (cv::norm(rvec) > 100.0) fail(source, "rvec", "longer than 100 (its length is the rotation angle in radians)");
  if (cv::norm(tvec) > kMaxTranslation) fail(source, "tvec", "farther than " + formatNumber(kMaxTranslation, 6) + " m");
  if (!distorted()) return;
  // The renderer inverts the distortion model at every pixel and draws a pinhole image widened
  // to cover the distorted frame: the border decides both (cheap: 2 (w + h) pixels).
  std::vector<cv::Vec2d> border;
  for (int u = 0; u < width; ++u) border.emplace_back(u, 0), border.emplace_back(u, height - 1);
  for (int v = 0; v < height; ++v) border.emplace_back(0, v), border.emplace_back(width - 1, v);
  cv::Mat pixels(static_cast<int>(border.size()), 1, CV_64FC2, border.data()), normal;
  std::vector<unsigned char> valid;
  undistortPixels(*this, pixels, normal, valid);
  double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
  for (std::size_t i = 0; i < border.size(); ++i) {
    if (!valid[i])
      fail(source, "distortion_coefficients",
           "the lens model cannot be inverted at image pixel (" + formatNumber(border[i][0], 6) + ", " +
               formatNumber(border[i][1], 6) +
               ") within one image size of extra field: distortion too strong for this image");
    const cv::Vec2d p = normal.at<cv::Vec2d>(static_cast<int>(i));
    xmin = std::min(xmin, p[0]), xmax = std::max(xmax, p[0]);
    ymin = std::min(ymin, p[1]), ymax = std::max(ymax, p[1]);
  }
  const double w = (xmax - xmin) * k(0, 0) + 5, h = (ymax - ymin) * k(1, 1) + 5;
  if (w > kMaxPinholeSide || h > kMaxPinholeSide)
    fail(source, "distortion_coefficients",
         "the undistorted image covering this lens would need " + formatNumber(std::ceil(w), 6) + "x" +
             formatNumber(std::ceil(h), 6) + " pixels, more than " + std::to_string(kMaxPinholeSide) + " a side");
}

Camera loadCamera(const std::string& path, CameraPose pose) {
  const std::string text = readCameraFile(path);
  const CameraNodes nodes(path);
  Camera c;
  try {
    const YAML::Node root = nodes.load(checkCameraText(text, path));
    if (!root.IsMap())
      nodes.failAtNode(root, "document", "the top level must be a mapping of camera fields (image_width: ...)");
    c.width = nodes.size(root, "image_width");
    c.height = nodes.size(root, "image_height");
    const cv::Mat k = nodes.matrix(root, "camera_matrix");
    if (k.rows != 3 || k.cols != 3) nodes.failAtNode(root["camera_matrix"], "camera_matrix", "must be 3x3");
    c.camera_matrix = cv::Matx33d(k);
    const cv::Mat d = nodes.matrix(root, "distortion_coefficients");
    if (d.rows != 1 && d.cols != 1)
      nodes.failAtNode(root["distortion_coefficients"], "distortion_coefficients", "must be a row or a column");
    c.distortion.assign(d.begin<double>(), d.end<double>());
    const bool has_pose = root["rvec"].IsDefined() || root["tvec"].IsDefined();
    if (has_pose || pose == CameraPose::Required) {
      c.rvec = nodes.vec3(root, "rvec");
      c.tvec = nodes.vec3(root, "tvec");
    }
    if (const YAML::Node f = root["frame"]) {
      if (!f.IsScalar() || f.Scalar().empty() || f.Scalar().size() > 256 || printable(f.Scalar()) != f.Scalar())
        nodes.failAtNode(f, "frame", "expected the name of a joint, body or link of the model (the camera's mount)");
      c.frame = f.Scalar();
    }
    c.reprojection_rms_px = nodes.quality(root, "reprojection_rms_px");
    c.rotation_sigma_deg = nodes.quality(root, "rotation_sigma_deg");
    c.position_sigma_m = nodes.quality(root, "position_sigma_m");
  } catch (const CameraError&) {
    throw;
  } catch (const InputError& e) {  // the YAML checks: syntax, documents, repeated keys, nesting
    throw CameraError(e.location(), e.problem());
  } catch (const YAML::Exception& e) {
    fail(path, "yaml", "cannot read it (" + printable(e.msg, 60) + ")");
  }
  c.validate(path);
  return c;
}

std::string cameraText(const Camera& camera) {
  cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  fs << "image_width" << camera.width << "image_height" << camera.height;
  fs << "camera_matrix" << cv::Mat(camera.camera_matrix);
  // No coefficients means none (OpenCV's reading of an empty list): written as five zeros, which
  // the reader accepts and which project the same.
  const std::vector<double> distortion = camera.distortion.empty() ? std::vector<double>(5, 0.0) : camera.distortion;
  fs << "distortion_coefficients" << cv::Mat(distortion).reshape(1, 1);
  fs << "rvec" << cv::Mat(camera.rvec) << "tvec" << cv::Mat(camera.tvec);
  if (!camera.frame.empty()) fs << "frame" << camera.frame;
  if (camera.reprojection_rms_px) fs << "reprojection_rms_px" << *camera.reprojection_rms_px;
  if (camera.rotation_sigma_deg) fs << "rotation_sigma_deg" << *camera.rotation_sigma_deg;
  if (camera.position_sigma_m) fs << "position_sigma_m" << *camera.position_sigma_m;
  return fs.releaseAndGetString();
}

void saveCamera(const Camera& camera, const std::string& path) {
  const std::string text = cameraText(camera);
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw CameraError(path + ": cannot write camera file");
  const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  if (std::fclose(f) != 0 || !ok) throw CameraError(path + ": cannot write camera file");
}

}  // namespace kccd::calib
