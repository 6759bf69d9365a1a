// The check job (`kccd check`, kccd.check_log): a joint log alone — a CSV state log, a robot
// log's joint states or a dataset episode's state rows — queried sample by sample, without a camera
// or video: the overlay's report, timeline and exit statuses for logs that have no pictures.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "kccd/braking.hpp"
#include "kccd/input_error.hpp"
#include "kccd/model.hpp"
#include "kccd/overlay/recording/overlay_recording.hpp"

namespace kccd::overlay {

/// Everything a check is asked, under the names every front end uses. Empty strings and zeros mean
/// "not given"; the defaults are the command line's.
struct CheckRequest {
  // The joint log: a CSV state log, a robot log or a dataset's episode.
  std::string states;                           ///< a CSV state log
  std::vector<std::string> ignore_columns;      ///< with states: columns skipped
  std::string bag;                              ///< a robot log's joint states instead
  std::string joint_topic;                      ///< with bag (default: the only one)
  std::string time_source = "header";           ///< with bag: "header" or "log"
  std::string joint_map;                        ///< with bag or lerobot: a joint map file
  std::string lerobot;                          ///< a LeRobot dataset's folder instead (with episode)
  long episode = -1;                            ///< with lerobot: the episode_index
  std::string state_key = "observation.state";  ///< with lerobot: the vector feature read as the state
  // Which times and which query.
  double rate = 0.0;                     ///< samples per second on a grid from the first sample (0: every sample)
  double max_gap = 0.0;                  ///< with rate: the largest log gap bridged (s; 0: 1.5 x the median period)
  std::string query = "distances";       ///< "distances" (every pair: the overlay's) or "collision" (faster)
  bool swept = false;                    ///< braking-interval volumes
  std::optional<BrakingParams> braking;  ///< with swept, every joint (default kOverlayBraking)
  int jobs = 0;                          ///< threads, 0 ... 256 (0: every core)
  // What is written (empty: not written), each staged and renamed when complete.
  std::string report;      ///< .json: the overlay's report format, one record per sample
  std::string timeline;    ///< .png
  std::string model_file;  ///< the model's file, when it came from one: no output may replace it
};

/// What a check found: the overlay's report with one record per sample (time on the log's clock),
/// and its JSON as the report file holds it.
struct CheckResult {
  OverlayReport report;
  nlohmann::json json;
  std::vector<std::string> warnings;  ///< the log's (a joint not read, timestamps off the grid, ...)
  std::string query;                  ///< the query run
};

/// Checks every field of `request` (the first problem: an InputError with the field, spelled by
/// `spell`, and no source), reading nothing.
void checkCheckRequest(const CheckRequest& request, const FieldSpelling& spell = {});

/// Checks the request and the outputs, reads the log, queries every sample (or the rate's grid)
/// on `jobs` threads, and writes the report and the timeline (staged; none on an error).
/// `progress` is called now and then with the samples done. Throws InputError, OutputError.
CheckResult runCheck(const CheckRequest& request, const Model& model, const FieldSpelling& spell = {},
                     const std::function<void(std::size_t done, std::size_t total)>& progress = {});

}  // namespace kccd::overlay
