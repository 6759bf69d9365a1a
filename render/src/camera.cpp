#include "kccd/render/camera.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

namespace kccd::render {
namespace {

constexpr int kDistortionSizes[] = {4, 5, 8, 12, 14};

[[noreturn]] void fail(const std::string& source, const std::string& field, const std::string& problem) {
  throw CameraError(source + ": " + field + ": " + problem);
}

cv::Mat readMatrix(const cv::FileStorage& fs, const std::string& source, const char* field) {
  const cv::FileNode node = fs[field];
  if (node.empty()) fail(source, field, "missing");
  cv::Mat m;
  try {
    node >> m;
  } catch (const cv::Exception&) {
    m.release();
  }
  if (m.empty() || m.channels() != 1) fail(source, field, "not an OpenCV matrix (!!opencv-matrix with rows, cols, dt, data)");
  m.convertTo(m, CV_64F);
  return m;
}

int readSize(const cv::FileStorage& fs, const std::string& source, const char* field) {
  const cv::FileNode node = fs[field];
  if (node.empty()) fail(source, field, "missing");
  if (!node.isInt()) fail(source, field, "not an integer");
  const int v = static_cast<int>(node);
  if (v <= 0 || v > 16384) fail(source, field, std::to_string(v) + " is not in 1..16384");
  return v;
}

cv::Vec3d readVec3(const cv::FileStorage& fs, const std::string& source, const char* field) {
  const cv::Mat m = readMatrix(fs, source, field);
  if (m.total() != 3) fail(source, field, "needs 3 values, has " + std::to_string(m.total()));
  return {m.at<double>(0), m.at<double>(1), m.at<double>(2)};
}

}  // namespace

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
  if (width <= 0 || width > 16384) fail(source, "image_width", "not in 1..16384");
  if (height <= 0 || height > 16384) fail(source, "image_height", "not in 1..16384");
  const cv::Matx33d& k = camera_matrix;
  for (int i = 0; i < 9; ++i)
    if (!std::isfinite(k.val[i])) fail(source, "camera_matrix", "non-finite value");
  if (!(k(0, 0) > 0.0) || !(k(1, 1) > 0.0)) fail(source, "camera_matrix", "focal lengths fx, fy must be > 0");
  if (k(0, 1) != 0.0) fail(source, "camera_matrix", "skew (row 0, column 1) must be 0");
  if (k(1, 0) != 0.0 || k(2, 0) != 0.0 || k(2, 1) != 0.0 || k(2, 2) != 1.0)
    fail(source, "camera_matrix", "must have the form [fx 0 cx; 0 fy cy; 0 0 1]");
  if (!std::count(std::begin(kDistortionSizes), std::end(kDistortionSizes), static_cast<int>(distortion.size())))
    fail(source, "distortion_coefficients", "needs 4, 5, 8, 12 or 14 values, has " + std::to_string(distortion.size()));
  for (double d : distortion)
    if (!std::isfinite(d)) fail(source, "distortion_coefficients", "non-finite value");
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(rvec[i])) fail(source, "rvec", "non-finite value");
    if (!std::isfinite(tvec[i])) fail(source, "tvec", "non-finite value");
  }
}

Camera loadCamera(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw CameraError(path + ": cannot open camera file (no such file)");
  cv::FileStorage fs;
  try {
    if (!fs.open(path, cv::FileStorage::READ | cv::FileStorage::FORMAT_YAML))
      throw CameraError(path + ": cannot open camera file");
  } catch (const cv::Exception& e) {
    throw CameraError(path + ": not a readable OpenCV YAML file (" + e.msg + ")");
  }
  Camera c;
  c.width = readSize(fs, path, "image_width");
  c.height = readSize(fs, path, "image_height");
  const cv::Mat k = readMatrix(fs, path, "camera_matrix");
  if (k.rows != 3 || k.cols != 3) fail(path, "camera_matrix", "must be 3x3");
  c.camera_matrix = cv::Matx33d(k);
  const cv::Mat d = readMatrix(fs, path, "distortion_coefficients");
  if (d.rows != 1 && d.cols != 1) fail(path, "distortion_coefficients", "must be a row or a column");
  c.distortion.assign(d.begin<double>(), d.end<double>());
  c.rvec = readVec3(fs, path, "rvec");
  c.tvec = readVec3(fs, path, "tvec");
  c.validate(path);
  return c;
}

void saveCamera(const Camera& camera, const std::string& path) {
  cv::FileStorage fs(path, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
  if (!fs.isOpened()) throw CameraError(path + ": cannot write camera file");
  fs << "image_width" << camera.width << "image_height" << camera.height;
  fs << "camera_matrix" << cv::Mat(camera.camera_matrix);
  fs << "distortion_coefficients" << cv::Mat(camera.distortion).reshape(1, 1);
  fs << "rvec" << cv::Mat(camera.rvec) << "tvec" << cv::Mat(camera.tvec);
}

Projection::Projection(const Camera& camera, double supersample)
    : camera_(camera), supersample_(supersample), world_to_camera_(camera.worldToCamera()) {
  camera_.validate("camera");
  if (!(supersample >= 1.0 && supersample <= 4.0)) throw CameraError("supersample must be in 1..4");
  const double s = supersample;
  const double fx = camera.camera_matrix(0, 0), fy = camera.camera_matrix(1, 1);
  const double cx = camera.camera_matrix(0, 2), cy = camera.camera_matrix(1, 2);
  pinhole_.fx = s * fx;
  pinhole_.fy = s * fy;
  if (!camera.distorted()) {
    // Same frame, scaled: output pixel u covers pinhole pixels around s (u + 0.5) - 0.5.
    pinhole_.cx = s * (cx + 0.5) - 0.5;
    pinhole_.cy = s * (cy + 0.5) - 0.5;
    pinhole_.width = static_cast<int>(std::lround(s * camera.width));
    pinhole_.height = static_cast<int>(std::lround(s * camera.height));
    warps_ = s != 1.0;
    if (warps_) {
      map_x_.create(camera.height, camera.width, CV_32F);
      map_y_.create(camera.height, camera.width, CV_32F);
      for (int v = 0; v < camera.height; ++v)
        for (int u = 0; u < camera.width; ++u) {
          map_x_.at<float>(v, u) = static_cast<float>(s * (u + 0.5) - 0.5);
          map_y_.at<float>(v, u) = static_cast<float>(s * (v + 0.5) - 0.5);
        }
    }
    return;
  }
  // Normalised coordinates of every output pixel centre (the inverse of the distortion model).
  const int n = camera.width * camera.height;
  cv::Mat pixels(n, 1, CV_64FC2), normal;
  for (int v = 0, i = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u, ++i) pixels.at<cv::Vec2d>(i) = cv::Vec2d(u, v);
  cv::undistortPoints(pixels, normal, camera.camera_matrix, camera.distortion, cv::noArray(), cv::noArray(),
                          cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-10));
  // Keep only the pixels the inversion really solved (checked by distorting again).
  cv::Mat xyz(n, 1, CV_64FC3), back;
  for (int i = 0; i < n; ++i) {
    const cv::Vec2d p = normal.at<cv::Vec2d>(i);
    xyz.at<cv::Vec3d>(i) = cv::Vec3d(p[0], p[1], 1.0);
  }
  cv::projectPoints(xyz, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), camera.camera_matrix, camera.distortion, back);
  // At most one image width / height of extra field on each side.
  const double x_lo = -(cx + 0.5) / fx - camera.width / fx, x_hi = (camera.width - cx - 0.5) / fx + camera.width / fx;
  const double y_lo = -(cy + 0.5) / fy - camera.height / fy, y_hi = (camera.height - cy - 0.5) / fy + camera.height / fy;
  std::vector<unsigned char> valid(n, 0);
  double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
  for (int v = 0, i = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u, ++i) {
      const cv::Vec2d p = normal.at<cv::Vec2d>(i), b = back.at<cv::Vec2d>(i);
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || std::hypot(b[0] - u, b[1] - v) > 1e-3) continue;
      if (p[0] < x_lo || p[0] > x_hi || p[1] < y_lo || p[1] > y_hi) continue;
      valid[i] = 1;
      xmin = std::min(xmin, p[0]), xmax = std::max(xmax, p[0]);
      ymin = std::min(ymin, p[1]), ymax = std::max(ymax, p[1]);
    }
  if (xmin > xmax) throw CameraError("camera: the distortion model cannot be inverted anywhere in the image");
  const double pad = 2.0;
  pinhole_.cx = -xmin * pinhole_.fx + pad;
  pinhole_.cy = -ymin * pinhole_.fy + pad;
  pinhole_.width = static_cast<int>(std::ceil((xmax - xmin) * pinhole_.fx + 2 * pad)) + 1;
  pinhole_.height = static_cast<int>(std::ceil((ymax - ymin) * pinhole_.fy + 2 * pad)) + 1;
  warps_ = true;
  map_x_.create(camera.height, camera.width, CV_32F);
  map_y_.create(camera.height, camera.width, CV_32F);
  for (int v = 0, i = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u, ++i) {
      const cv::Vec2d p = normal.at<cv::Vec2d>(i);
      map_x_.at<float>(v, u) = valid[i] ? static_cast<float>(p[0] * pinhole_.fx + pinhole_.cx) : -1e6f;
      map_y_.at<float>(v, u) = valid[i] ? static_cast<float>(p[1] * pinhole_.fy + pinhole_.cy) : -1e6f;
    }
}

std::array<float, 16> Projection::glMatrix(double near, double far) const {
  const Pinhole& p = pinhole_;
  std::array<float, 16> m{};
  m[0] = static_cast<float>(2.0 * p.fx / p.width);
  m[5] = static_cast<float>(2.0 * p.fy / p.height);
  m[8] = static_cast<float>(2.0 * (p.cx + 0.5) / p.width - 1.0);
  m[9] = static_cast<float>(2.0 * (p.cy + 0.5) / p.height - 1.0);
  m[10] = static_cast<float>((far + near) / (far - near));
  m[11] = 1.0f;
  m[14] = static_cast<float>(-2.0 * far * near / (far - near));
  return m;
}

Eigen::Vector2d Projection::pinholePixel(const Vec3& world, double near, double far) const {
  const Vec3 c = world_to_camera_ * world;
  const double x = static_cast<float>(c.x()), y = static_cast<float>(c.y()), z = static_cast<float>(c.z());
  const std::array<float, 16> m = glMatrix(near, far);
  const double xc = m[0] * x + m[8] * z, yc = m[5] * y + m[9] * z, wc = m[11] * z;
  const double xw = (xc / wc + 1.0) * 0.5 * pinhole_.width, yw = (yc / wc + 1.0) * 0.5 * pinhole_.height;
  return {xw - 0.5, yw - 0.5};
}

Eigen::Vector2d Projection::project(const Vec3& world) const {
  const Eigen::Vector2d p = pinholePixel(world);
  if (!camera_.distorted()) return (p.array() + 0.5) / supersample_ - 0.5;
  const cv::Vec3d normal((p.x() - pinhole_.cx) / pinhole_.fx, (p.y() - pinhole_.cy) / pinhole_.fy, 1.0);
  std::vector<cv::Point2d> out;
  cv::projectPoints(std::vector<cv::Vec3d>{normal}, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), camera_.camera_matrix,
                    camera_.distortion, out);
  return {out[0].x, out[0].y};
}

}  // namespace kccd::render
