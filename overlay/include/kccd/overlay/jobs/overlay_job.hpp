// The overlay job as every front end asks for it (`kccd overlay`, kccd.overlay_recording,
// kccd.batch): one request of named fields, checked once, its logs read, run and written.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "kccd/braking.hpp"
#include "kccd/calib/camera.hpp"
#include "kccd/input_error.hpp"
#include "kccd/model.hpp"
#include "kccd/overlay/recording/overlay_recording.hpp"

namespace kccd::overlay {

/// Everything an overlay run is asked, under the names every front end uses (Python's keywords).
/// Empty strings and zeros mean "not given"; the defaults are the command line's.
struct OverlayRequest {
  // The recording: a video with its state log, a robot log, or a dataset's episode.
  std::string video;                            ///< a video file or image-sequence pattern (with states)
  std::string states;                           ///< the state log, CSV (with video)
  std::vector<std::string> ignore_columns;      ///< state log columns skipped (each must exist)
  std::string frame_times;                      ///< CSV 'frame,time' (with video; default index / fps)
  std::string bag;                              ///< a robot log instead of video, states and frame_times
  std::string image_topic, joint_topic;         ///< with bag (default: the only one of its type)
  std::string time_source = "header";           ///< with bag: "header" or "log"
  std::string joint_map;                        ///< with bag or lerobot: a joint map file
  std::string lerobot;                          ///< a LeRobot dataset's folder instead (with episode)
  long episode = -1;                            ///< with lerobot: the episode_index
  std::string camera_key;                       ///< with lerobot: its camera (default: the only one)
  std::string state_key = "observation.state";  ///< with lerobot: the vector feature read as the state
  std::string frame_by = "auto";                ///< with lerobot: auto, timestamp or index (lerobot_recording.hpp)
  // Frames against the log's clock.
  double fps = 0.0;                                             ///< the video's frame rate (0: its own)
  double time_offset = 0.0;                                     ///< log time = frame time + offset (s)
  std::optional<std::pair<double, double>> time_offset_search;  ///< search [lo, hi] instead (parseTimeOffset)
  double max_gap = 0.0;  ///< largest log gap bridged (s; 0: 1.5 x the median period)
  // What is checked and drawn.
  bool swept = false;                    ///< braking-interval volumes
  std::optional<BrakingParams> braking;  ///< with swept, every joint (default kOverlayBraking)
  bool plain = false;                    ///< volumes only: no legend, no status line
  std::string legend = "auto";           ///< auto, outside, off or a corner (legendPlaceOf; not with plain)
  bool visuals = false;                  ///< also the model's visual geometry
  std::string masks;                     ///< a folder of robot masks, or "auto"
  std::vector<std::string> mask_bodies;  ///< the bodies the masks show (default all)
  std::string frames;                    ///< "FIRST:END:STEP" drawn (all are checked)
  int jobs = 0;                          ///< drawing threads, 0 ... 256 (0: every core)
  bool timings = false;                  ///< where the time went, in the report
  // What is written (empty: not written), each staged and renamed when complete.
  std::string output;                           ///< .mp4, .mkv or .avi
  std::string codec;                            ///< its FourCC (default by extension)
  std::string png_dir;                          ///< frame_NNNNNN.png into a new or empty folder
  std::string report, contact_sheet, timeline;  ///< .json, .png, .png
  int contact_frames = 12;                      ///< frames on the contact sheet, 1 ... 64
  // The model's and camera's files, when they came from files: no output may replace them.
  std::string model_file, camera_file;
};

/// "S" (seconds) sets `request.time_offset`; "auto:A:B" (A < B) sets its search (the job checks
/// that each is within 1e9). Throws InputError on the field "time_offset".
void parseTimeOffset(const std::string& text, OverlayRequest& request);

/// Checks every field of `request` as OverlayJob does, reading nothing (no file is opened; without
/// a model, the fields that need one, visuals and mask_bodies, are not checked). Throws the first
/// problem: an InputError with the field, spelled by `spell`, and no source.
void checkOverlayRequest(const OverlayRequest& request, const Model* model, const FieldSpelling& spell = {});

/// A request checked and its logs read, ready to run once.
class OverlayJob {
 public:
  /// Checks every field (the first problem: an InputError with the field, spelled by `spell`, and
  /// no source), the outputs (checkOverlayOutputs, before anything is read), then reads the state
  /// log or robot log, the joint map and the masks' folder. Nothing is decoded or written.
  /// `model` and `camera` must outlive the job.
  OverlayJob(const OverlayRequest& request, const Model& model, const calib::Camera& camera, FieldSpelling spell = {});
  ~OverlayJob();
  OverlayJob(const OverlayJob&) = delete;
  OverlayJob& operator=(const OverlayJob&) = delete;

  /// The robot log's warnings (e.g. a logged joint not read), for the front end to show.
  const std::vector<std::string>& warnings() const;

  /// What a run found, and its JSON as the report file holds it (with every frame, naming the
  /// files written).
  struct Result {
    OverlayReport report;
    nlohmann::json json;
  };
  /// Every frame checked, drawn and handed on; the outputs committed when all are done (on an
  /// error none is). Throws as overlayRecording and writeOverlayOutputs do.
  Result run(const std::function<void(const OverlayProgress&)>& progress = {});

 private:
  struct State;
  std::unique_ptr<State> s_;
};

}  // namespace kccd::overlay
