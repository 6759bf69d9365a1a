#include "kccd/overlay/datasets/dataset_info.hpp"

#include <filesystem>
#include <map>
#include <string>

#include "kccd/input_error.hpp"

namespace kccd::overlay {

nlohmann::json datasetInfoJson(const logs::LerobotDataset& d) {
  using nlohmann::json;
  std::int64_t frames = 0;
  json episodes = json::array();
  std::map<std::string, int> present;
  for (const logs::LerobotEpisode& e : d.episodes) {
    frames += e.length;
    json videos = json::object(), files = json::object();
    for (const std::string& key : d.cameras()) {
      const logs::LerobotFeature& f = *d.feature(key);
      if (f.dtype != "video") continue;
      std::error_code ec;
      bool exists = false;
      try {
        const std::string file = d.video(e, key).file;
        exists = std::filesystem::is_regular_file(file, ec);
        files[key] = file;
      } catch (const InputError&) {
      }
      videos[key] = exists;
      present[key] += exists ? 1 : 0;
    }
    json data = nullptr;
    try {
      data = d.dataFile(e);
    } catch (const InputError&) {
    }
    episodes.push_back({{"episode", e.index},
                        {"length", e.length},
                        {"seconds", static_cast<double>(e.length) / d.fps},
                        {"tasks", e.tasks},
                        {"videos", videos},
                        {"files", {{"data", data}, {"videos", files}}}});
  }
  json cameras = json::array(), vectors = json::array(), others = json::array();
  for (const logs::LerobotFeature& f : d.features) {
    if (f.isCamera()) {
      json c = {{"key", f.key}, {"dtype", f.dtype}, {"width", f.width}, {"height", f.height}};
      if (f.dtype == "video") {
        c["codec"] = f.codec;
        c["pix_fmt"] = f.pix_fmt;
        c["fps"] = f.fps > 0 ? f.fps : d.fps;
        c["videos_present"] = present[f.key];
      }
      cameras.push_back(c);
    } else if (f.shape.size() == 1 && f.shape[0] > 1) {
      vectors.push_back({{"key", f.key}, {"dtype", f.dtype}, {"size", f.shape[0]}, {"names", f.names}});
    } else {
      others.push_back({{"key", f.key}, {"dtype", f.dtype}, {"shape", f.shape}});
    }
  }
  return {{"dataset", d.root},
          {"format", "LeRobot"},
          {"version", d.version},
          {"robot_type", d.robot_type},
          {"fps", d.fps},
          {"episodes", static_cast<std::int64_t>(d.episodes.size())},
          {"frames", frames},
          {"seconds", static_cast<double>(frames) / d.fps},
          {"vectors", vectors},
          {"cameras", cameras},
          {"other_features", others},
          {"tasks", d.tasks},
          {"warnings", d.warnings},
          {"episode_list", episodes}};
}

}  // namespace kccd::overlay
