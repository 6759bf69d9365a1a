// What a LeRobot dataset holds (`kccd dataset info`, kccd.read_lerobot's "info"): its metadata
// summarised, and which episodes' videos are on disk.
#pragma once

#include <nlohmann/json.hpp>

#include "kccd/logs/lerobot_dataset.hpp"

namespace kccd::overlay {

/// The dataset as docs/formats.md's dataset info JSON: version, robot type, fps, episodes (count,
/// frames, seconds, and per episode its length, tasks, which cameras' videos exist and its files:
/// the Parquet table and each camera's video), the state
/// and action features (names, sizes), the cameras (key, dtype, codec, size, fps, videos present),
/// the other features, the tasks, and the warnings opening it gave.
nlohmann::json datasetInfoJson(const logs::LerobotDataset& dataset);

}  // namespace kccd::overlay
