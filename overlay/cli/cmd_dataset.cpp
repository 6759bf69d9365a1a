// `kccd dataset info DIR [--json]`: what a robot-learning dataset (LeRobot) holds.
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "commands.hpp"
#include "kccd/logs/lerobot_dataset.hpp"
#include "kccd/overlay/datasets/dataset_info.hpp"

namespace kccd::cli {
namespace {

struct DatasetInfoArgs {
  std::string dataset;
  bool json = false;
};

std::string number(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string joined(const nlohmann::json& names, std::size_t most) {
  std::string out;
  std::size_t n = 0;
  for (const auto& name : names) {
    if (n++ == most) return out + ", ... (" + std::to_string(names.size()) + " in all)";
    out += (out.empty() ? "" : ", ") + name.get<std::string>();
  }
  return out;
}

Exit runDatasetInfo(const DatasetInfoArgs& args) {
  const logs::LerobotDataset d = logs::openLerobotDataset(args.dataset);
  const nlohmann::json j = overlay::datasetInfoJson(d);
  for (const std::string& w : d.warnings) std::cerr << "kccd dataset info: warning: " << w << "\n";
  if (args.json) {
    std::cout << j.dump(1) << "\n";
    return Exit::Ok;
  }
  std::cout << d.root << ": LeRobot " << d.version << (d.robot_type.empty() ? "" : ", robot " + d.robot_type) << ", "
            << number(d.fps) << " fps\n";
  std::cout << j["episodes"].get<std::int64_t>() << " episodes, " << j["frames"].get<std::int64_t>() << " frames ("
            << number(j["seconds"].get<double>()) << " s)";
  if (!d.episodes.empty()) {
    std::int64_t lo = d.episodes.front().length, hi = lo;
    for (const logs::LerobotEpisode& e : d.episodes) lo = std::min(lo, e.length), hi = std::max(hi, e.length);
    std::cout << "; episodes " << d.episodes.front().index << " ... " << d.episodes.back().index << ", " << lo
              << " ... " << hi << " frames each";
  }
  std::cout << "\n";
  if (!d.tasks.empty()) std::cout << "tasks (" << d.tasks.size() << "): " << joined(d.tasks, 5) << "\n";
  std::cout << "\nvectors (a state or action: --state-key):\n";
  for (const auto& v : j["vectors"])
    std::cout << "  " << v["key"].get<std::string>() << "  " << v["dtype"].get<std::string>() << "["
              << v["size"].get<std::int64_t>() << "]"
              << (v["names"].empty() ? std::string("  (no names)") : "  " + joined(v["names"], 12)) << "\n";
  std::cout << "\ncameras (--camera-key):\n";
  if (j["cameras"].empty()) std::cout << "  none\n";
  for (const auto& c : j["cameras"]) {
    std::cout << "  " << c["key"].get<std::string>() << "  " << c["dtype"].get<std::string>();
    if (c.contains("codec")) std::cout << " " << c["codec"].get<std::string>();
    std::cout << "  " << c["width"].get<int>() << "x" << c["height"].get<int>();
    if (c.contains("videos_present"))
      std::cout << ", videos of " << c["videos_present"].get<int>() << " of " << d.episodes.size()
                << " episodes present";
    std::cout << "\n";
  }
  return Exit::Ok;
}

}  // namespace

Runner addDataset(CLI::App& app) {
  CLI::App* dataset =
      app.add_subcommand("dataset", "Robot-learning datasets (LeRobot v2.0, v2.1 and v3.0): what a dataset holds");
  dataset->require_subcommand(1);
  auto args = std::make_shared<DatasetInfoArgs>();
  CLI::App* info = dataset->add_subcommand(
      "info",
      "A LeRobot dataset as downloaded (meta/info.json, the episode list, Parquet tables, videos): version, robot "
      "type, fps, episodes (count, frames, duration), the vector features (state, action) with their names and "
      "sizes, the cameras (codec, size, how many episodes' videos are on disk) and the tasks. What strays from the "
      "format is said in one warning line each. Its episodes go to kccd overlay and kccd check with --lerobot DIR "
      "--episode N.");
  info->add_option("dataset", args->dataset, "The dataset's folder (the one holding meta/)")->required();
  info->add_flag("--json", args->json, "Machine-readable output, with every episode");
  return [args] { return runDatasetInfo(*args); };
}

}  // namespace kccd::cli
