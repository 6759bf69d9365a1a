// `kccd check MODEL (--states CSV | --bag LOG | --lerobot DIR --episode N)`: a joint log checked
// sample by sample without a camera (kccd::overlay::runCheck does the work; this file reads the
// options into its request and prints).
#include <cmath>
#include <iostream>
#include <memory>

#include "cli_args.hpp"
#include "cli_files.hpp"
#include "cli_model.hpp"
#include "cli_output.hpp"
#include "cli_progress.hpp"
#include "commands.hpp"
#include "kccd/overlay/jobs/check_job.hpp"
#include "kccd/overlay/recording/overlay_recording.hpp"

namespace kccd::cli {
namespace {

struct CheckArgs {
  overlay::CheckRequest request;
  std::string model, ignore_columns;
  BrakingParams braking = overlay::kOverlayBraking;
  bool braking_given = false;
  bool quiet = false, json = false;
};

const std::map<std::string, std::string> kCheckSpelling = {
    {"braking", "--latency, --deceleration, --max-acceleration, --position-error and --velocity-error"}};
std::string checkSpelled(const std::string& field) { return optionSpelling(field, kCheckSpelling); }

Exit runCheckCommand(CheckArgs& a) {
  overlay::CheckRequest& q = a.request;
  const Model model = loadOrExplain(a.model);
  q.model_file = a.model;
  q.ignore_columns = splitCommas(a.ignore_columns);
  if (a.braking_given) q.braking = a.braking;
  Progress progress("check", a.quiet || a.json);
  const overlay::CheckResult result =
      overlay::runCheck(q, model, checkSpelled, [&](std::size_t done, std::size_t total) {
        progress.update(total ? static_cast<double>(done) / static_cast<double>(total) : 1.0,
                        std::to_string(done) + "/" + std::to_string(total) + " samples");
      });
  progress.finish();
  for (const std::string& w : result.warnings) std::cerr << "kccd check: warning: " << w << "\n";
  const overlay::OverlayReport& r = result.report;
  const std::size_t samples = result.json["samples"].get<std::size_t>();
  if (a.json) {
    nlohmann::json j = result.json;
    j.erase("frames");
    j["seconds"] = r.seconds;
    j["samples_per_second"] = r.seconds > 0 ? static_cast<double>(samples) / r.seconds : 0.0;
    std::cout << j.dump(2) << "\n";
  } else if (!a.quiet) {
    std::cout << "check: " << samples << " samples (" << result.query << (q.swept ? ", swept" : ", static")
              << "); clear " << r.clear << ", within margin " << r.within_margin << ", colliding " << r.colliding
              << ", no state " << r.no_state << "; "
              << format(static_cast<double>(samples) / std::max(r.seconds, 1e-9), 4) << " samples/s with " << r.jobs
              << " jobs\n";
    if (!q.report.empty()) std::cout << "report: " << q.report << "\n";
    if (!q.timeline.empty()) std::cout << "timeline: " << q.timeline << "\n";
  }
  if (r.unsafe > 0) {
    std::cerr << "kccd: " << r.unsafe << " sample(s) with an unsafe query status";
    if (const std::optional<std::size_t> first = r.firstUnsafe()) {
      const overlay::FrameRecord& f = r.frames[*first];
      std::cerr << ", first sample " << *first << " (t = " << format(f.time, 6)
                << " s): " << (f.braking_failed ? "no braking box (non-finite state or velocity)" : toString(f.query));
    }
    std::cerr << " (unsafe; everything was written)\n";
    return Exit::Unsafe;
  }
  return Exit::Ok;
}

}  // namespace

Runner addCheck(CLI::App& app) {
  auto a = std::make_shared<CheckArgs>();
  CLI::App* sub = app.add_subcommand(
      "check",
      "A joint log checked without a camera: every sample (or --rate's grid) of a CSV state log, a robot log's joint "
      "states or a LeRobot dataset's episode queried, static or --swept; the overlay's report, timeline and exit "
      "statuses");
  sub->add_option("model", a->model, "Model file (YAML, kccd: 1)")->required();
  sub->add_option("--states", a->request.states, "State log (CSV: time and one column per state value, see kccd info)");
  sub->add_option("--ignore-columns", a->ignore_columns,
                  "With --states: comma-separated columns to skip (an unknown column is an error)");
  sub->add_option(
      "--bag", a->request.bag,
      "A robot log's joint states instead (MCAP, rosbag2 .db3 or folder, ROS 1 .bag; no image topic needed)");
  sub->add_option("--joint-topic", a->request.joint_topic,
                  "With --bag: the sensor_msgs/JointState topic (default: the only one)");
  sub->add_option("--time-source", a->request.time_source, "With --bag: header or log")->capture_default_str();
  addLerobotOptions(*sub, a->request.lerobot, a->request.episode, a->request.state_key);
  sub->add_option("--joint-map", a->request.joint_map,
                  "With --bag or --lerobot: YAML (kccd_joint_map: 1) renaming, scaling (degrees, a range) or fixing "
                  "state values (see docs/formats.md)");
  sub->add_option("--rate", a->request.rate,
                  "Query on a grid of this many samples per second from the first sample (1e-6 ... 1e6; 0: every "
                  "sample of the log)")
      ->capture_default_str();
  sub->add_option("--max-gap", a->request.max_gap,
                  "With --rate: no state when no two samples this close bracket the time (s; 0: 1.5 x the median "
                  "period)")
      ->capture_default_str();
  sub->add_option("--query", a->request.query,
                  "distances: every pair's bound (the overlay's query; the report's distances are tight near the "
                  "margin); collision: only whether any pair is within the margin, warm-started from the last "
                  "sample (faster; its distances are bounds that may be looser)")
      ->capture_default_str();
  sub->add_flag("--swept", a->request.swept,
                "Check the braking-interval swept volumes (from logged or differenced velocities)");
  addBrakingOptions(*sub, a->braking);
  sub->add_option("--report", a->request.report,
                  "Per-sample report (.json, the overlay's format): state match, status, min distance, pairs");
  sub->add_option("--timeline", a->request.timeline,
                  "A .png of the log over time: the smallest bound and the margin, the spans within the margin or "
                  "colliding listed with their link pairs");
  sub->add_option("-j,--jobs", a->request.jobs, "Threads, 0 ... 256 (0: hardware threads)")->capture_default_str();
  sub->add_flag("--json", a->json, "Print the summary as JSON");
  sub->add_flag("-q,--quiet", a->quiet, "No progress and no summary");
  sub->footer(
      "Exit status: 0 checked (whatever the distances), 2 bad input (nothing written), 3 a sample's query status is\n"
      "unsafe (everything still written).");
  return [a, sub] {
    a->braking_given = brakingGiven(*sub);
    return runCheckCommand(*a);
  };
}

}  // namespace kccd::cli
