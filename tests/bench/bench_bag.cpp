// Reading a recording from a robot log against reading it from a video file, measured in one run:
// makes 1280x720 frames (textured, so the codecs do real work) and a 1 kHz state log of the humanoid,
// writes them as
//   - a ROS 2 MCAP bag by other projects' writers (tests/bags/write_recording.mjs: each frame a
//     sensor_msgs CompressedImage of its JPEG file, quality 90; each state a JointState; zstd
//     chunks of 1 MiB),
//   - the JPEG files themselves as an image sequence (f_%06d.jpg: the same bytes, the same decoding
//     work: the baseline),
//   - an MJPG .avi (FFmpeg's, at its own quality) and an mp4v .mp4 of the frames (the codec
//     bench_overlay uses),
// then times (best of R rounds, each run in turn)
//   1. reading the bag as kccd overlay --bag reads it: the joint states matched to the model's
//      joints, then every frame decoded (kccd::overlay::readBagRecording and its frames),
//   2. reading the files: the state log CSV parsed, then every frame of the sequence decoded (as
//      kccd overlay --video reads it); and of the .avi and the .mp4,
//   3. `kccd overlay --bag` against `kccd overlay --video f_%06d.jpg --states --frame-times` (the
//      same frames, the same states, -o .mp4), frames per second and the ratio.
// Usage: bench_bag KCCD_BINARY NODE WRITER_MJS [--frames N] [--repeat R] [--dir WORKDIR]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "bench/bench_recording.hpp"
#include "kccd/overlay/bags/bag_recording.hpp"
#include "kccd/overlay/recording/frame_times.hpp"
#include "kccd/overlay/recording/video_source.hpp"
#include "kccd/state_log.hpp"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

void run(const std::string& command) {
  if (std::system(command.c_str()) != 0) throw std::runtime_error("failed: " + command);
}

// Frames decoded from a source, and a checksum of the first so the work cannot be skipped.
std::size_t drain(kccd::overlay::FrameSource& source) {
  cv::Mat f;
  std::size_t n = 0;
  while (source.read(f)) ++n;
  return n;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::cerr << "usage: bench_bag KCCD_BINARY NODE WRITER_MJS [--frames N] [--repeat R] [--dir WORKDIR]\n";
    return 2;
  }
  const std::string kccd = argv[1], node = argv[2], writer = argv[3];
  int frames = 300, repeat = 3;
  std::string dir = (fs::temp_directory_path() / "kccd_bench_bag").string();
  for (int i = 4; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--frames")
      frames = std::stoi(v);
    else if (k == "--repeat")
      repeat = std::max(1, std::stoi(v));
    else if (k == "--dir")
      dir = v;
  }
  try {
    fs::create_directories(dir);
    const double fps = 30.0;
    const std::string model_path = std::string(KCCD_DATA_DIR) + "/humanoid.yaml", camera = dir + "/camera.yaml",
                      states = dir + "/states.csv", times = dir + "/times.csv", bag = dir + "/rec.mcap",
                      avi = dir + "/rec.avi", mp4 = dir + "/rec.mp4";
    const kccd::Model model = kccd::loadModel(model_path);
    kccd::calib::saveCamera(kccd::bench::benchCamera(), camera);
    kccd::bench::makeLog(states, model, frames / fps + 0.5, 1000);
    {
      std::ofstream t(times);
      t << "frame,time\n";
      cv::VideoWriter va(avi, cv::CAP_FFMPEG, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps, cv::Size(1280, 720),
                         true);
      cv::VideoWriter vm(mp4, cv::CAP_FFMPEG, cv::VideoWriter::fourcc('m', 'p', '4', 'v'), fps, cv::Size(1280, 720),
                         true);
      if (!va.isOpened() || !vm.isOpened()) throw std::runtime_error("cannot write the videos in " + dir);
      cv::RNG rng(7);
      char name[64];
      for (int i = 0; i < frames; ++i) {
        const cv::Mat f = kccd::bench::texturedFrame(i, rng);
        std::snprintf(name, sizeof name, "/f_%06d.jpg", i);
        cv::imwrite(dir + name, f, {cv::IMWRITE_JPEG_QUALITY, 90});
        va.write(f);
        vm.write(f);
        std::snprintf(name, sizeof name, "%d,%d.%06d\n", i, i / 30, (i % 30) * 100000 / 3);
        t << name;
      }
    }
    run(node + " " + writer + " " + bag + " --images " + dir + "/f_%06d.jpg --frame-times " + times + " --states " +
        states + " --compression zstd > /dev/null");

    const std::string sequence = dir + "/f_%06d.jpg";
    double bag_read = 1e300, seq_read = 1e300, avi_read = 1e300, mp4_read = 1e300, over_bag = 1e300, over_files = 1e300;
    std::size_t bag_frames = 0, seq_frames = 0, avi_frames = 0, mp4_frames = 0, joint_rows = 0, csv_rows = 0,
                time_rows = 0;
    const std::string overlay =
        kccd + " overlay " + model_path + " --camera " + camera + " --quiet -o " + dir + "/out.mp4";
    for (int round = 0; round < repeat; ++round) {
      auto t0 = Clock::now();
      {
        const kccd::overlay::BagRecording rec = kccd::overlay::readBagRecording({.bag = bag}, model);
        const auto source = rec.open_frames();
        bag_frames = drain(*source);
        joint_rows = rec.log.rows();
      }
      bag_read = std::min(bag_read, since(t0));
      for (auto [path, best, count] :
           {std::tuple{&sequence, &seq_read, &seq_frames}, std::tuple{&avi, &avi_read, &avi_frames},
            std::tuple{&mp4, &mp4_read, &mp4_frames}}) {
        t0 = Clock::now();
        const kccd::StateLog log = kccd::loadStateLog(states, model);
        time_rows = kccd::overlay::loadFrameTimes(times).size();
        kccd::overlay::VideoSource source(*path);
        *count = drain(source);
        csv_rows = log.rows();
        *best = std::min(*best, since(t0));
      }
      t0 = Clock::now();
      run(overlay + " --bag " + bag);
      over_bag = std::min(over_bag, since(t0));
      t0 = Clock::now();
      run(overlay + " --video " + sequence + " --states " + states + " --frame-times " + times);
      over_files = std::min(over_files, since(t0));
    }
    const auto mb = [&](const std::string& p) { return static_cast<double>(fs::file_size(p)) / 1e6; };
    std::printf(
        "bench_bag: %d frames 1280x720 (JPEG q90) and %zu joint states at 1 kHz of the humanoid (20 joints); best of "
        "%d\n",
        frames, joint_rows, repeat);
    std::printf("  files: bag %.1f MB (zstd chunks), MJPG .avi %.1f MB, mp4v .mp4 %.1f MB, states.csv %.1f MB\n",
                mb(bag), mb(avi), mb(mp4), mb(states));
    std::printf("  read the bag (joint states matched, every frame decoded): %7.3f s  %6.1f fps\n", bag_read,
                bag_frames / bag_read);
    std::printf(
        "  read states.csv + the same JPEGs as an image sequence:    %7.3f s  %6.1f fps  (the bag %.2f x as fast)\n",
        seq_read, seq_frames / seq_read, seq_read / bag_read);
    std::printf(
        "  read states.csv + an MJPG .avi (FFmpeg's quality):        %7.3f s  %6.1f fps  (the bag %.2f x as fast)\n",
        avi_read, avi_frames / avi_read, avi_read / bag_read);
    std::printf(
        "  read states.csv + the mp4v .mp4:                          %7.3f s  %6.1f fps  (the bag %.2f x as fast)\n",
        mp4_read, mp4_frames / mp4_read, mp4_read / bag_read);
    std::printf("  kccd overlay --bag:                                       %7.3f s  %6.1f fps\n", over_bag,
                frames / over_bag);
    std::printf(
        "  kccd overlay --video f_%%06d.jpg --states --frame-times:   %7.3f s  %6.1f fps  (--bag at %.0f %% of its "
        "rate)\n",
        over_files, frames / over_files, 100.0 * over_files / over_bag);
    std::printf(
        "{\"frames\": %d, \"joint_states\": %zu, \"bag_read_s\": %.4f, \"sequence_read_s\": %.4f, \"avi_read_s\": "
        "%.4f, \"mp4_read_s\": %.4f, "
        "\"overlay_bag_s\": %.4f, \"overlay_files_s\": %.4f, \"bag_vs_sequence\": %.3f, \"bag_vs_avi\": %.3f, "
        "\"bag_vs_mp4\": %.3f, "
        "\"overlay_ratio\": %.3f}\n",
        frames, joint_rows, bag_read, seq_read, avi_read, mp4_read, over_bag, over_files, seq_read / bag_read,
        avi_read / bag_read, mp4_read / bag_read, over_files / over_bag);
    if (bag_frames != static_cast<std::size_t>(frames) || seq_frames != bag_frames || avi_frames != bag_frames ||
        mp4_frames != bag_frames || csv_rows != joint_rows || time_rows != bag_frames)
      std::fprintf(stderr,
                   "bench_bag: the readers disagree: %zu, %zu, %zu, %zu frames (%zu frame times); %zu, %zu states\n",
                   bag_frames, seq_frames, avi_frames, mp4_frames, time_rows, joint_rows, csv_rows);
  } catch (const std::exception& e) {
    std::cerr << "bench_bag: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
