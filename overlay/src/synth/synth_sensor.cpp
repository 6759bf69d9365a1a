// Frames of a synthetic recording (kccd/overlay/synth/synth_sensor.hpp): the robot drawn over the
// background, the sensor model and the writer thread.
#include "kccd/overlay/synth/synth_sensor.hpp"
#include "kccd/calib/image_encode.hpp"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <mutex>
#include <thread>
#include <utility>

#include <opencv2/imgproc.hpp>

#include "kccd/overlay/synth/synth.hpp"
#include "kccd/render/composite.hpp"
#include "kccd/render/scene.hpp"

namespace kccd::overlay {
namespace {

using Clock = std::chrono::steady_clock;

double sensorSeconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

}  // namespace

VideoFormat videoFormat(const std::string& codec) {
  if (codec == "ffvhuff") return {"video.mkv", "FFVH"};
  if (codec == "ffv1") return {"video.mkv", "FFV1"};
  if (codec == "mjpg") return {"video.avi", "MJPG"};
  if (codec == "mp4v") return {"video.mp4", "mp4v"};
  throw SynthError(InputLocation{{}, 0, 0, "codec"}, "expected ffvhuff, ffv1, mjpg or mp4v, got '" + codec + "'");
}

cv::Scalar bodyColour(const Model& m, std::size_t i) {
  if (m.bodies[i].frame == kWorld) return {92, 96, 100};
  static const cv::Scalar palette[] = {{222, 222, 226}, {150, 152, 158}, {190, 120, 60}, {205, 208, 212}};
  return palette[i % 4];
}

FramePainter::FramePainter(const Model& m, const calib::Camera& camera) : model_(m), camera_(camera) {
  options_.supersample = 2.0;
  options_.mask_supersample = 2.0;
  view_ = std::make_unique<render::ModelView>(m, camera, options_);
  for (std::size_t b = 0; b < m.bodies.size(); ++b) colours_.push_back(bodyColour(m, b));
}

void FramePainter::setAppearance(std::vector<render::LoadedVisual> visuals, double volume_scale) {
  use_visuals_ = !visuals.empty();
  scale_ = volume_scale;
  view_.reset();  // one GL context at a time
  view_ = std::make_unique<render::ModelView>(model_, camera_, options_, std::move(visuals));
}

render::Frame FramePainter::robot(std::span<const double> q) {
  render::ModelViewRequest request;
  request.state = q;
  request.tight_volumes = false;
  request.volumes = !use_visuals_;  // the visuals, or the volumes at the visible scale
  request.visuals = use_visuals_;
  request.radius_scale = scale_;
  request.colours = colours_;
  request.style.shaded = true;
  request.style.legend = false;
  return view_->draw(request).images;
}

cv::Mat FramePainter::fullMask(std::span<const double> q) {
  render::ModelViewRequest request;
  request.state = q;
  request.tight_volumes = false;
  request.colour = false;
  request.colours = colours_;
  request.style.shaded = true;
  request.style.legend = false;
  return view_->draw(request).images.mask;
}

cv::Mat FramePainter::draw(const cv::Mat& background, std::span<const double> q, cv::Mat& mask) {
  const render::Frame f = robot(q);
  cv::Mat frame = background.clone();
  render::compositeOver(frame, f.bgra);
  mask = f.mask;
  return frame;
}

cv::Mat vignetteGain(const calib::Camera& camera) {
  cv::Mat gain(camera.height, camera.width, CV_8UC3);
  const double cx = camera.camera_matrix(0, 2), cy = camera.camera_matrix(1, 2);
  const double half_diagonal2 =
      0.25 * (static_cast<double>(camera.width) * camera.width + static_cast<double>(camera.height) * camera.height);
  for (int v = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u) {
      const double r2 = ((u - cx) * (u - cx) + (v - cy) * (v - cy)) / half_diagonal2;
      gain.at<cv::Vec3b>(v, u) = cv::Vec3b::all(cv::saturate_cast<uchar>(255.0 * (1.0 - 0.25 * std::min(r2, 2.0))));
    }
  return gain;
}

// The frame pipeline's second stage (vignetting, blur, noise, encoding) runs on its own thread
// while the next frame renders.
struct SensorWriter::Impl {
  Impl(VideoFileWriter& video, std::string mask_dir, double blur, double noise, std::uint64_t seed)
      : video_(video), mask_dir_(std::move(mask_dir)), blur_(blur), noise_(noise), seed_(seed), thread_([this] {
          loop();
        }) {}
  void push(int index, cv::Mat frame, cv::Mat mask) {
    std::unique_lock<std::mutex> lock(mutex_);
    space_.wait(lock, [&] { return queue_.size() < 2; });
    queue_.push_back({index, std::move(frame), std::move(mask)});
    ready_.notify_one();
  }
  void setVignette(cv::Mat gain) {
    const std::lock_guard<std::mutex> lock(mutex_);
    vignette_ = std::move(gain);
  }
  void setFrameSink(std::function<void(int, const cv::Mat&)> sink) {
    const std::lock_guard<std::mutex> lock(mutex_);
    sink_ = std::move(sink);
  }
  void finish() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
      ready_.notify_one();
    }
    if (thread_.joinable()) thread_.join();
  }

  struct Item {
    int index;
    cv::Mat frame, mask;
  };
  void loop() {
    for (;;) {
      Item item;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        ready_.wait(lock, [&] { return !queue_.empty() || done_; });
        if (queue_.empty()) return;
        item = std::move(queue_.front());
        queue_.pop_front();
        space_.notify_one();
      }
      if (!error_.empty()) continue;
      try {
        process(item);
      } catch (const std::exception& e) {  // OpenCV's encoders throw cv::Exception
        error_ = std::string("frame ") + std::to_string(item.index) + ": " + e.what();
      }
    }
  }
  // Vignetting, blur and noise, then the video frame, the mask file and the frame sink.
  void process(Item& item) {
    const auto t0 = Clock::now();
    cv::Mat f = item.frame;
    if (!vignette_.empty()) cv::multiply(f, vignette_, f, 1.0 / 255.0);
    if (blur_ > 0) cv::GaussianBlur(f, f, cv::Size(0, 0), blur_, blur_, cv::BORDER_REFLECT);
    const auto t1 = Clock::now();
    if (noise_ > 0) {
      // Gaussian noise drawn once for a field 64 px larger than the frame; each frame takes it
      // at its own seeded offset (drawing 2.8 M normal numbers per frame cost 25 ms).
      constexpr int kPad = 64;
      if (noise_field_.empty()) {
        noise_field_.create(f.rows + kPad, f.cols + kPad, CV_16SC3);
        cv::RNG rng(seed_ * 1000003ull + 7);
        rng.fill(noise_field_, cv::RNG::NORMAL, 0.0, noise_);
      }
      cv::RNG rng(seed_ * 1000003ull + static_cast<std::uint64_t>(item.index) + 11);
      const int dx = rng.uniform(0, kPad), dy = rng.uniform(0, kPad);
      cv::Mat noisy;
      f.convertTo(noisy, CV_16SC3);
      if (rng.uniform(0, 2) == 0)
        noisy += noise_field_(cv::Rect(dx, dy, f.cols, f.rows));
      else
        noisy -= noise_field_(cv::Rect(dx, dy, f.cols, f.rows));
      noisy.convertTo(f, CV_8UC3);
    }
    const auto t2 = Clock::now();
    try {
      video_.write(f);
    } catch (const VideoFileError& e) {
      error_ = std::string("cannot write the video (") + e.what() + ")";
      return;
    }
    const auto t3 = Clock::now();
    char name[32];
    std::snprintf(name, sizeof name, "frame_%06d.png", item.index);
    std::vector<std::uint8_t> png;
    try {
      png = calib::encodePng(item.mask, 1);
    } catch (const calib::ImageEncodeError&) {
      error_ = std::string("cannot encode mask ") + name;
      return;
    }
    // A new file in the temporary folder (the folder's rename publishes it).
    std::FILE* file = std::fopen((mask_dir_ + "/" + name).c_str(), "wb");
    const bool ok = file && std::fwrite(png.data(), 1, png.size(), file) == png.size();
    if (file && std::fclose(file) != 0) error_ = std::string("cannot write mask ") + name;
    if (!ok) error_ = std::string("cannot write mask ") + name;
    if (!error_.empty()) return;
    const auto t4 = Clock::now();
    if (sink_) sink_(item.index, f);
    stage_s_[0] += sensorSeconds(t0, t1), stage_s_[1] += sensorSeconds(t1, t2), stage_s_[2] += sensorSeconds(t2, t3),
        stage_s_[3] += sensorSeconds(t3, t4);
    ++written_;
  }
  VideoFileWriter& video_;
  std::string mask_dir_;
  cv::Mat vignette_, noise_field_;
  std::function<void(int, const cv::Mat&)> sink_;
  std::array<double, 4> stage_s_{};
  double blur_, noise_;
  std::uint64_t seed_;
  std::mutex mutex_;
  std::condition_variable ready_, space_;
  std::deque<Item> queue_;
  bool done_ = false;
  int written_ = 0;
  std::string error_;
  std::thread thread_;  // last: started once every other member is ready
};

SensorWriter::SensorWriter(VideoFileWriter& video, std::string mask_dir, double blur, double noise, std::uint64_t seed)
    : impl_(std::make_unique<Impl>(video, std::move(mask_dir), blur, noise, seed)) {}
SensorWriter::~SensorWriter() { impl_->finish(); }
void SensorWriter::setVignette(cv::Mat gain) { impl_->setVignette(std::move(gain)); }
void SensorWriter::setFrameSink(std::function<void(int, const cv::Mat&)> sink) { impl_->setFrameSink(std::move(sink)); }
void SensorWriter::push(int index, cv::Mat frame, cv::Mat mask) {
  impl_->push(index, std::move(frame), std::move(mask));
}
void SensorWriter::finish() { impl_->finish(); }
int SensorWriter::written() const { return impl_->written_; }
const std::array<double, 4>& SensorWriter::stageSeconds() const { return impl_->stage_s_; }
const std::string& SensorWriter::error() const { return impl_->error_; }

}  // namespace kccd::overlay
