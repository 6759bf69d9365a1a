// Throughput of `kccd overlay` next to a plain transcode of the same video with the same codec,
// measured in one run: makes a 1280x720 recording of the humanoid (mp4v .mp4, textured frames so
// the codec does real work) with a 100 Hz state log, then times
//   1. the plain transcode: decode -> encode, pipelined on two threads (the baseline),
//   2. `kccd overlay` with static volumes,
//   3. `kccd overlay --swept`,
// and prints frames per second and the ratios. Each is also run on a short clip, the first K
// frames of the same recording (K = frames / 10, at least 10): the difference of the two times
// is what the frames beyond K cost, so (frames - K) / (T_frames - T_K) is the rate a long
// recording runs at once started (the overlay's process start, model, log and lens set-up left
// out; the transcode's opening likewise), and T_K - K / rate the fixed cost. With --baseline
// OTHER_KCCD (e.g. the previous build) the same two runs of that binary are timed in between,
// and the ratios to it printed.
// Usage:
//   bench_overlay KCCD_BINARY [--frames N] [--jobs J] [--dir WORKDIR] [--codec mp4v|MJPG|FFV1]
//                 [--baseline OTHER_KCCD] [--repeat R (rounds, each run's fastest kept; default 3)]
#include <array>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <sys/resource.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <nlohmann/json.hpp>

#include "bench/bench_recording.hpp"
#include "kccd/calib/camera.hpp"
#include "kccd/model.hpp"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// CPU seconds (user + system) of this process's threads, or of its waited-for children.
double cpuSeconds(int who) {
  rusage r{};
  getrusage(who, &r);
  return static_cast<double>(r.ru_utime.tv_sec + r.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(r.ru_utime.tv_usec + r.ru_stime.tv_usec);
}

// A command's (or the transcode's) fastest wall time, and its CPU time in that round.
struct Timed {
  double wall = 1e300, cpu = 0.0;
  bool keep(double w, double c) {
    if (w >= wall) return false;
    wall = w, cpu = c;
    return true;
  }
};

int fourcc(const std::string& codec) { return cv::VideoWriter::fourcc(codec[0], codec[1], codec[2], codec[3]); }

std::string extensionFor(const std::string& codec) {
  if (codec == "FFV1") return ".mkv";
  if (codec == "MJPG") return ".avi";
  return ".mp4";
}

// The recording (`frames` frames) and a short clip of its first `short_frames` frames.
void makeVideos(const std::string& path, const std::string& short_path, const std::string& codec, int frames,
                int short_frames, double fps) {
  cv::VideoWriter vw(path, cv::CAP_FFMPEG, fourcc(codec), fps, cv::Size(1280, 720), true);
  cv::VideoWriter clip(short_path, cv::CAP_FFMPEG, fourcc(codec), fps, cv::Size(1280, 720), true);
  if (!vw.isOpened()) throw std::runtime_error("cannot write " + path);
  if (!clip.isOpened()) throw std::runtime_error("cannot write " + short_path);
  cv::RNG rng(7);
  for (int i = 0; i < frames; ++i) {
    const cv::Mat f = kccd::bench::texturedFrame(i, rng);
    vw.write(f);
    if (i < short_frames) clip.write(f);
  }
}

// A look's rate once started, from its whole run (n frames) and the short clip's (k frames):
// frames per second beyond the first k, and the fixed cost (seconds) that rate leaves over.
struct Steady {
  double fps = 0.0, fixed = 0.0;
};

Steady steadyOf(double t_n, int n, double t_k, int k) {
  Steady s;
  s.fps = t_n > t_k ? (n - k) / (t_n - t_k) : 0.0;
  s.fixed = s.fps > 0.0 ? t_k - k / s.fps : 0.0;
  return s;
}

// Decode and encode on two threads with a bounded queue: the plain transcode's best.
double transcode(const std::string& in, const std::string& out, const std::string& codec, int& frames) {
  const auto t0 = Clock::now();
  cv::VideoCapture cap(in, cv::CAP_FFMPEG);
  cv::VideoWriter vw(out, cv::CAP_FFMPEG, fourcc(codec), cap.get(cv::CAP_PROP_FPS), cv::Size(1280, 720), true);
  std::mutex mu;
  std::condition_variable cv;
  std::deque<cv::Mat> queue;
  bool done = false;
  std::thread reader([&] {
    for (;;) {
      cv::Mat f;
      const bool ok = cap.read(f);
      std::unique_lock lock(mu);
      cv.wait(lock, [&] { return queue.size() < 8; });
      if (!ok) {
        done = true;
        cv.notify_all();
        return;
      }
      queue.push_back(std::move(f));
      cv.notify_all();
    }
  });
  frames = 0;
  for (;;) {
    cv::Mat f;
    {
      std::unique_lock lock(mu);
      cv.wait(lock, [&] { return !queue.empty() || done; });
      if (queue.empty()) break;
      f = std::move(queue.front());
      queue.pop_front();
      cv.notify_all();
    }
    vw.write(f);
    ++frames;
  }
  reader.join();
  vw.release();
  return since(t0);
}

// Runs a command, returns its wall time; its standard output into `out` when given.
double runOverlay(const std::string& command, std::string* out = nullptr) {
  const auto t0 = Clock::now();
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) throw std::runtime_error("cannot run: " + command);
  std::string text;
  char buf[4096];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, pipe)) > 0;) text.append(buf, n);
  const int rc = pclose(pipe);
  const double s = since(t0);
  if (rc != 0) throw std::runtime_error("failed (" + std::to_string(rc) + "): " + command);
  if (out) *out = text;
  return s;
}

// This build's per-stage times (kccd overlay --timings --json), ms per frame, as a table row.
struct Stages {
  double setup = 0.0;
  std::vector<std::pair<std::string, double>> ms;
};

Stages stagesOf(const std::string& json, int frames) {
  const nlohmann::json j = nlohmann::json::parse(json);
  Stages s;
  const nlohmann::json& t = j.at("timings");
  s.setup = t.at("setup").get<double>();
  for (const char* k : {"decode", "state", "query", "render", "read_back", "warp", "composite", "encode"})
    s.ms.emplace_back(k, 1000.0 * t.at("stage_seconds").at(k).get<double>() / frames);
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: bench_overlay KCCD_BINARY [--frames N] [--jobs J] [--dir WORKDIR] [--codec mp4v|MJPG|FFV1] "
                 "[--baseline OTHER_KCCD] [--repeat R]\n";
    return 2;
  }
  const std::string kccd = argv[1];
  int frames = 150, jobs = 0, repeat = 3;
  std::string dir = (fs::temp_directory_path() / "kccd_bench_overlay").string(), codec = "mp4v", baseline;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--frames")
      frames = std::stoi(v);
    else if (k == "--repeat")
      repeat = std::max(1, std::stoi(v));
    else if (k == "--jobs")
      jobs = std::stoi(v);
    else if (k == "--dir")
      dir = v;
    else if (k == "--codec")
      codec = v;
    else if (k == "--baseline")
      baseline = v;
  }
  try {
    fs::create_directories(dir);
    const double fps = 30.0;
    const std::string ext = extensionFor(codec);
    const std::string model = std::string(KCCD_DATA_DIR) + "/humanoid.yaml", camera = dir + "/camera.yaml",
                      video = dir + "/in" + ext, clip = dir + "/short" + ext, log = dir + "/states.csv";
    const int clip_frames = std::max(10, frames / 10);
    if (frames < 2 * clip_frames) throw std::runtime_error("--frames: at least 20");
    kccd::calib::saveCamera(kccd::bench::benchCamera(), camera);
    kccd::bench::makeLog(log, kccd::loadModel(model), frames / fps + 1.0);
    makeVideos(video, clip, codec, frames, clip_frames, fps);

    int plain_frames = 0, clip_plain_frames = 0;
    const std::string common =
        " --camera " + camera + " --states " + log + " --quiet" + (jobs > 0 ? " --jobs " + std::to_string(jobs) : "");
    const std::string args = " overlay " + model + " --video " + video + common;
    const std::string short_args = " overlay " + model + " --video " + clip + common;
    const std::string base = kccd + args;
    // Rounds of: transcode, then per look the baseline's run and this build's (alternating, so a
    // change in the machine's load falls on all of them), then the short clip's; each keeps its
    // fastest round (the least disturbed by other work on a shared machine).
    const std::string other = baseline + args;
    Timed plain, stat_base, stat, swept_base, swept, clip_plain, clip_stat, clip_swept;
    std::string stat_json, swept_json;
    // A command's wall time, and the CPU its process used (the children's CPU clock moves when it is waited for).
    auto run = [&](Timed& best, const std::string& command, std::string* json) {
      const double c0 = cpuSeconds(RUSAGE_CHILDREN);
      std::string text;
      const double wall = runOverlay(command, json ? &text : nullptr);
      if (best.keep(wall, cpuSeconds(RUSAGE_CHILDREN) - c0) && json) *json = text;
    };
    for (int round = 0; round < repeat; ++round) {
      const double c0 = cpuSeconds(RUSAGE_SELF);
      const double wall = transcode(video, dir + "/plain" + ext, codec, plain_frames);
      plain.keep(wall, cpuSeconds(RUSAGE_SELF) - c0);
      if (!baseline.empty()) run(stat_base, other + " -o " + dir + "/base_static" + ext + " --codec " + codec, nullptr);
      run(stat, base + " --timings --json -o " + dir + "/static" + ext + " --codec " + codec, &stat_json);
      if (!baseline.empty())
        run(swept_base, other + " --swept -o " + dir + "/base_swept" + ext + " --codec " + codec, nullptr);
      run(swept, base + " --swept --timings --json -o " + dir + "/swept" + ext + " --codec " + codec, &swept_json);
      const double c1 = cpuSeconds(RUSAGE_SELF);
      const double clip_wall = transcode(clip, dir + "/plain_short" + ext, codec, clip_plain_frames);
      clip_plain.keep(clip_wall, cpuSeconds(RUSAGE_SELF) - c1);
      run(clip_stat, kccd + short_args + " -o " + dir + "/static_short" + ext + " --codec " + codec, nullptr);
      run(clip_swept, kccd + short_args + " --swept -o " + dir + "/swept_short" + ext + " --codec " + codec, nullptr);
    }
    if (clip_plain_frames != clip_frames)
      throw std::runtime_error("the short clip's transcode saw " + std::to_string(clip_plain_frames) + " frames, not " +
                               std::to_string(clip_frames));
    const Steady s_plain = steadyOf(plain.wall, plain_frames, clip_plain.wall, clip_frames);
    const Steady s_stat = steadyOf(stat.wall, frames, clip_stat.wall, clip_frames);
    const Steady s_swept = steadyOf(swept.wall, frames, clip_swept.wall, clip_frames);
    const Stages stat_stages = stagesOf(stat_json, frames), swept_stages = stagesOf(swept_json, frames);

    const unsigned hw = std::thread::hardware_concurrency();
    const double f_plain = plain_frames / plain.wall, f_static = frames / stat.wall, f_swept = frames / swept.wall;
    std::printf("bench_overlay: %d frames 1280x720, codec %s, humanoid (26 bodies), %u hardware threads, jobs %s\n",
                frames, codec.c_str(), hw, jobs > 0 ? std::to_string(jobs).c_str() : "default");
    // CPU per frame: every thread's user + system time (a 2-core machine has 2 ms of CPU per ms of wall time).
    auto cpu = [](const Timed& t, int n) { return 1000.0 * t.cpu / n; };
    std::printf("  plain transcode (decode + encode): %7.1f fps                          CPU %5.1f ms per frame\n",
                f_plain, cpu(plain, plain_frames));
    std::printf("  kccd overlay, static volumes:      %7.1f fps  (%3.0f %% of the transcode)  CPU %5.1f ms per frame\n",
                f_static, 100 * f_static / f_plain, cpu(stat, frames));
    std::printf("  kccd overlay --swept:              %7.1f fps  (%3.0f %% of the transcode)  CPU %5.1f ms per frame\n",
                f_swept, 100 * f_swept / f_plain, cpu(swept, frames));
    // Once started: what each further frame costs (a long recording's rate), and the fixed cost.
    std::printf("  once started (frames %d..%d against the first %d alone), frames per second and fixed cost:\n",
                clip_frames, frames, clip_frames);
    std::printf("    plain transcode:                 %7.1f fps                          fixed %.3f s\n", s_plain.fps,
                s_plain.fixed);
    std::printf("    kccd overlay, static volumes:    %7.1f fps  (%3.0f %% of the transcode)  fixed %.3f s\n",
                s_stat.fps, 100 * s_stat.fps / s_plain.fps, s_stat.fixed);
    std::printf("    kccd overlay --swept:            %7.1f fps  (%3.0f %% of the transcode)  fixed %.3f s\n",
                s_swept.fps, 100 * s_swept.fps / s_plain.fps, s_swept.fixed);
    // Where the time went (each stage on its own thread: decoding, annotating and encoding overlap).
    std::printf("  per frame, ms        static   swept   (set-up %.3f s and %.3f s)\n", stat_stages.setup,
                swept_stages.setup);
    for (std::size_t k = 0; k < stat_stages.ms.size(); ++k)
      std::printf("    %-12s    %7.2f %7.2f\n", stat_stages.ms[k].first.c_str(), stat_stages.ms[k].second,
                  swept_stages.ms[k].second);
    std::printf("    %-12s    %7.2f %7.2f\n", "transcode", 1000.0 * plain.wall / plain_frames,
                1000.0 * plain.wall / plain_frames);
    if (!baseline.empty()) {
      std::printf("  baseline %s, static volumes: %7.1f fps  (this build %.3f x as fast)  CPU %5.1f ms per frame\n",
                  baseline.c_str(), frames / stat_base.wall, stat_base.wall / stat.wall, cpu(stat_base, frames));
      std::printf("  baseline %s, --swept:        %7.1f fps  (this build %.3f x as fast)  CPU %5.1f ms per frame\n",
                  baseline.c_str(), frames / swept_base.wall, swept_base.wall / swept.wall, cpu(swept_base, frames));
    }
    std::printf(
        "{\"frames\": %d, \"codec\": \"%s\", \"plain_fps\": %.2f, \"static_fps\": %.2f, \"swept_fps\": %.2f, "
        "\"static_ratio\": %.3f, \"swept_ratio\": %.3f, \"plain_cpu_ms\": %.2f, \"static_cpu_ms\": %.2f, "
        "\"swept_cpu_ms\": %.2f, "
        "\"clip_frames\": %d, \"started_plain_fps\": %.2f, \"started_static_fps\": %.2f, \"started_swept_fps\": %.2f, "
        "\"started_static_ratio\": %.3f, \"started_swept_ratio\": %.3f, \"fixed_plain_s\": %.3f, \"fixed_static_s\": "
        "%.3f, "
        "\"fixed_swept_s\": %.3f}\n",
        frames, codec.c_str(), f_plain, f_static, f_swept, f_static / f_plain, f_swept / f_plain,
        cpu(plain, plain_frames), cpu(stat, frames), cpu(swept, frames), clip_frames, s_plain.fps, s_stat.fps,
        s_swept.fps, s_stat.fps / s_plain.fps, s_swept.fps / s_plain.fps, s_plain.fixed, s_stat.fixed, s_swept.fixed);
    if (plain_frames != frames)
      std::fprintf(stderr, "bench_overlay: the transcode saw %d frames, not %d\n", plain_frames, frames);
  } catch (const std::exception& e) {
    std::cerr << "bench_overlay: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
