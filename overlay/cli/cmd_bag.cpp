// `kccd bag info BAG [--json]`: what a robot log holds, per topic.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "cli_args.hpp"
#include "cli_output.hpp"
#include "commands.hpp"
#include "kccd/input_error.hpp"
#include "kccd/logs/bag_summary.hpp"
#include "kccd/overlay/bags/bag_export.hpp"
#include "kccd/overlay/bags/bag_info.hpp"

namespace kccd::cli {
namespace {

struct BagInfoArgs {
  std::string bag;
  bool json = false;
};

double seconds(std::uint64_t ns) { return 1e-9 * static_cast<double>(ns); }

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

Exit runBagInfo(const BagInfoArgs& args) {
  const logs::BagSummary b = logs::summarizeBag(args.bag);
  if (!b.damage.empty())
    std::cerr << "kccd bag info: warning: " << args.bag << ": " << b.damage << "; " << b.messages << " messages read\n";
  if (args.json) {
    const nlohmann::json j = overlay::bagInfoJson(b);
    std::cout << j.dump(1) << "\n";
    return Exit::Ok;
  }
  std::cout << b.path << ": " << b.format << (b.profile.empty() ? "" : ", profile " + b.profile)
            << (b.library.empty() ? "" : ", written by " + b.library) << "\n";
  std::cout << b.messages << " messages";
  if (b.messages > 0)
    std::cout << " over " << fixed(seconds(b.last_log_time - b.first_log_time), 3) << " s (log time "
              << fixed(seconds(b.first_log_time), 3) << " to " << fixed(seconds(b.last_log_time), 3) << ")";
  std::cout << "\n";
  if (!b.chunks.empty()) {
    std::cout << "chunks:";
    for (const auto& [c, n] : b.chunks) std::cout << " " << n << " " << c;
    std::cout << "\n";
  }
  std::cout
      << "\ntopics (log times from the first message's; skew: log time minus header stamp, min / median / max):\n";
  for (const logs::TopicSummary& t : b.topics) {
    std::cout << "  " << t.topic << "  " << (t.type.empty() ? "(no schema)" : t.type) << "  " << t.count
              << (t.count == 1 ? " message" : " messages");
    if (t.publishers.size() > 1) std::cout << " (" << t.publishers.size() << " publishers)";
    std::cout << (t.count == 1 ? " at " : " from ") << fixed(seconds(t.first_log_time - b.first_log_time), 3);
    if (t.count > 1) std::cout << " to " << fixed(seconds(t.last_log_time - b.first_log_time), 3);
    std::cout << " s";
    if (t.count > 1) std::cout << ", " << fixed(t.rate(), t.rate() >= 100 ? 1 : 3) << " Hz";
    if (t.stamped > t.zero_stamps)
      std::cout << ", skew " << fixed(1e3 * t.skew_min, 3) << " / " << fixed(1e3 * t.skew_median, 3) << " / "
                << fixed(1e3 * t.skew_max, 3) << " ms";
    if (t.zero_stamps > 0) std::cout << ", " << t.zero_stamps << " zero stamps";
    if (!t.no_stamps.empty()) std::cout << "  (stamps: " << t.no_stamps << ")";
    if (t.definition == "built in") std::cout << "  (definition built in: the log stores none)";
    std::cout << "\n";
  }
  return Exit::Ok;
}

struct BagExportArgs {
  overlay::BagExportOptions options;
  std::string time_source = "header";
  bool quiet = false;
};

Exit runBagExport(const BagExportArgs& args) {
  overlay::BagExportOptions o = args.options;
  o.time_source = *overlay::timeSourceOf(args.time_source);  // checked by the option
  o.spell = [](const std::string& field) { return optionSpelling(field); };
  const overlay::BagExportReport r = overlay::exportBag(o);
  for (const std::string& w : r.warnings) std::cerr << "kccd bag export: warning: " << w << "\n";
  if (args.quiet) return Exit::Ok;
  const std::string clock = o.time_source == overlay::TimeSource::Log ? "log times" : "header stamps";
  std::cout << "time 0 of the files: " << r.origin_ns << " ns (" << clock << ")\n";
  if (!o.states.empty())
    std::cout << o.states << ": " << r.states << " states of " << r.joints.size() << " joints from " << r.joint_topic
              << (r.velocities ? " (with velocities)" : "") << "\n";
  if (!o.video.empty())
    std::cout << o.video << ": " << r.frames << " frames " << r.width << "x" << r.height << " from " << r.image_topic
              << " (nominal " << fixed(r.fps, 3) << " fps; the times are in " << o.frame_times << ")\n";
  if (!o.camera_info.empty())
    std::cout << o.camera_info << ": intrinsics from " << r.camera_info_topic << " (for kccd calib --intrinsics)\n";
  return Exit::Ok;
}

}  // namespace

Runner addBag(CLI::App& app) {
  CLI::App* bag = app.add_subcommand(
      "bag", "Robot logs (MCAP, rosbag2 sqlite3, ROS 1 bags): what a log holds, and the log as this suite's own files");
  bag->require_subcommand(1);
  auto args = std::make_shared<BagInfoArgs>();
  CLI::App* info = bag->add_subcommand(
      "info",
      "Topics of a robot log: type, message count, first and last log time, rate, and per topic how far the "
      "messages' header stamps lie behind their log times (decoded from the definitions the log stores). A topic "
      "several nodes publish is one row with its publisher count (--json lists each publisher). Reads "
      "MCAP (ROS 2 CDR and ROS 1 messages; chunks none, zstd or lz4), rosbag2 sqlite3 (.db3) and ROS 1 bags (format "
      "2.0; chunks none, bz2 or lz4); a rosbag2 bag folder (with its metadata.yaml) of .db3 or MCAP files is read as "
      "one log, its split files in the order it lists. A log cut short is read up to the damage, with a warning naming "
      "where.");
  info->add_option("bag", args->bag, "The log: an .mcap, .db3 or .bag file, or a rosbag2 folder")->required();
  info->add_flag("--json", args->json, "Machine-readable output (times in nanoseconds as decimal strings)");
  auto ex = std::make_shared<BagExportArgs>();
  CLI::App* exp = bag->add_subcommand(
      "export",
      "Write a robot log as this suite's own files, so every other command works on it: joint states as a state log "
      "(--states, columns named as the first joint state names them, with .vel columns when every message gives "
      "velocities), camera images as a video (--video) with its frame-times file (--frame-times), camera info as an "
      "intrinsics file (--camera-info, for kccd calib --intrinsics). Times in seconds from the first exported "
      "message, on the header stamps (or the log times). All outputs appear together or not at all.");
  exp->add_option("bag", ex->options.bag, "The log: an .mcap, .db3 or .bag file, or a rosbag2 folder")->required();
  exp->add_option("--states", ex->options.states, "State log to write (.csv)");
  exp->add_option("--video", ex->options.video, "Video to write (.mkv lossless FFV1, .mp4 mp4v, .avi MJPG)");
  exp->add_option("--frame-times", ex->options.frame_times, "Frame-times file to write with --video (.csv)");
  exp->add_option("--camera-info", ex->options.camera_info, "Intrinsics file to write (.yaml)");
  exp->add_option("--joint-topic", ex->options.joint_topic, "sensor_msgs/JointState topic (default: the only one)");
  exp->add_option("--image-topic", ex->options.image_topic,
                  "sensor_msgs/Image or CompressedImage topic (default: the only one)");
  exp->add_option("--camera-info-topic", ex->options.camera_info_topic,
                  "sensor_msgs/CameraInfo topic (default: the only one)");
  exp->add_option(
         "--time-source", ex->time_source,
         "header: the messages' header stamps (the log time where a stamp is zero, with a warning); log: the times "
         "the recorder logged them")
      ->check(CLI::IsMember({"header", "log"}))
      ->default_str("header");
  exp->add_flag("--quiet,-q", ex->quiet, "Print only warnings and errors");
  return [args, ex, exp] {
    if (exp->parsed()) return runBagExport(*ex);
    return runBagInfo(*args);
  };
}

}  // namespace kccd::cli
