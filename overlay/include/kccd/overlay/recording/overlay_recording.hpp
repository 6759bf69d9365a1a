// The main job as one call: a recording and its state log in, every frame checked by the library's
// query, the drawn frames composited and handed to a sink in order, a report out.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json_fwd.hpp>
#include <opencv2/core/mat.hpp>

#include "kccd/braking.hpp"
#include "kccd/calib/camera.hpp"
#include "kccd/model.hpp"
#include "kccd/overlay/recording/frame_annotator.hpp"
#include "kccd/overlay/recording/frame_decoration.hpp"
#include "kccd/overlay/recording/frame_source.hpp"
#include "kccd/overlay/recording/mask_agreement.hpp"
#include "kccd/overlay/recording/time_offset.hpp"
#include "kccd/overlay/recording/video_sink.hpp"
#include "kccd/state_log.hpp"

namespace kccd::overlay {

/// The frames drawn and handed to the sink: first, first + step, ... before end (Python's slice;
/// end < 0: to the last frame). Every frame is still checked and reported.
struct FrameRange {
  long first = 0, end = -1, step = 1;
  bool contains(std::size_t index) const;
};

/// "FIRST", "FIRST:END" or "FIRST:END:STEP" (frame numbers from 0, END exclusive, each part
/// optional, STEP >= 1; empty: every frame). Throws InputError "LABEL TEXT: expected ...".
FrameRange parseFrameRange(const std::string& text, const std::string& label = "--frames");

/// What a run reads. The references must outlive the call; labels name the inputs in errors.
struct OverlayInputs {
  const Model& model;
  const calib::Camera& camera;
  const StateLog& log;
  std::string video;                ///< a video file or an image sequence pattern (VideoSource)
  std::vector<double> frame_times;  ///< each frame's time (s); empty: index / fps
  std::string video_label;          ///< e.g. "--video rec.mkv" (default: the path)
  std::string camera_label;         ///< e.g. the camera file's path (default "camera")
  std::string frame_times_label;    ///< e.g. "--frame-times t.csv"
  std::string no_rate_hint = "give the frame rate or the frame times";  ///< when the video declares no rate
  /// Opens the frames instead of `video` (e.g. a robot log's image topic, see bag_recording.hpp);
  /// called once per pass over the frames.
  std::function<std::unique_ptr<FrameSource>()> open_frames;
  /// Robot masks of the frames: each frame's FrameRecord::mask_iou, computed by the annotating threads.
  const MaskAgreement* masks = nullptr;
};

/// How a run checks and draws.
/// The braking a run assumes with `swept` unless told otherwise (kccd overlay's defaults): 10 ms of
/// latency, 5 rad/s^2 (or m/s^2) of guaranteed deceleration, every state value.
inline constexpr BrakingParams kOverlayBraking{.latency = 0.01, .deceleration = 5.0};

struct OverlayOptions {
  double time_offset = 0.0;  ///< log time = frame time + offset (s)
  /// Search [lo, hi] for the offset instead (findTimeOffset; a first pass over the video).
  std::optional<std::pair<double, double>> time_offset_search;
  std::string time_offset_label;            ///< names the search in errors (e.g. "--time-offset auto:0:1")
  double max_gap = 0.0;                     ///< the largest log gap bridged (s); <= 0: 1.5 x the median period
  double fps = 0.0;                         ///< the video's frame rate; <= 0: as the video declares
  bool swept = false;                       ///< braking-interval swept volumes (BrakingParams per joint)
  BrakingParams braking = kOverlayBraking;  ///< every state value's braking, with `swept`
  bool plain = false;                       ///< volumes only: no legend, no status line
  LegendPlace legend = LegendPlace::Auto;   ///< where the legend goes (Outside: the frames handed on are taller)
  bool visuals = false;                     ///< also draw the model's visual geometry at the logged state
  FrameRange frames;                        ///< the frames drawn and handed on
  int jobs = 0;                             ///< annotator threads (each with a GL context); <= 0: hardware threads
  std::size_t contact_frames = 0;           ///< frames on the contact sheet (0: none)
  int contact_tile_width = 320;             ///< pixels per contact sheet tile
  bool timings = false;                     ///< the report's JSON gives where the time went ("timings")
};

/// A run's progress, given after every frame in order.
struct OverlayProgress {
  std::size_t frames_done = 0;
  std::size_t frames_expected = 0;  ///< as the video declares (0: unknown)
  double frames_per_second = 0.0;
};

/// What a run found.
struct OverlayReport {
  std::vector<FrameRecord> frames;  ///< every decoded frame, in order
  std::size_t written = 0, clear = 0, within_margin = 0, colliding = 0, no_state = 0, unsafe = 0;
  double time_offset = 0.0;                                     ///< the offset used (found, with a search)
  std::optional<std::pair<double, double>> time_offset_search;  ///< the range searched, if any
  TimeOffset time_offset_found;                                 ///< what the search found (with a search)
  double max_gap = 0.0;                                         ///< the largest log gap bridged (s)
  double fps = 0.0;     ///< the frame rate used (0 with frame times and no declared rate)
  double margin = 0.0;  ///< the model's safety margin
  bool swept = false;
  int jobs = 0;
  double seconds = 0.0;        ///< the frame loop's wall time
  double setup_seconds = 0.0;  ///< before the first frame: inputs checked, lens maps, first pass
  StageTimes stages;           ///< every frame's StageTimes summed
  std::size_t reused =
      0;  ///< drawn frames whose state (and box) equalled their annotator's last: answer and layer reused
  bool timings = false;   ///< OverlayOptions::timings: reportJson gives setup_seconds and stages
  cv::Mat contact_sheet;  ///< selected frames, captioned (empty when none was asked or drawn)
  std::vector<std::size_t> contact_sheet_frames;  ///< the indices of the frames on it, in order
  /// How the recording was read (e.g. a robot log's file, topics, clock and time 0), written as
  /// the report's "source" object when not empty; empty values are left out.
  std::vector<std::pair<std::string, std::string>> source;
  /// Counts `record` in clear, within_margin, colliding, no_state and unsafe.
  void count(const FrameRecord& record);
  /// Index of the first unsafe frame, if any.
  std::optional<std::size_t> firstUnsafe() const;
};

/// Checks, draws and hands on every frame of a recording. Every input is checked before a frame is
/// decoded; frames are decoded by one thread, annotated by `jobs` threads and decorated
/// (decorateFrame: the legend's corner chosen in input order) and handed to `sink` in input order
/// on the calling thread, with at most 2 x jobs + 2 frames in memory. `sink` may be
/// null: the frames are then only checked, reported and put on the contact sheet. `progress` is
/// called after each frame. Throws an InputError-derived error naming the input and place (the
/// sink is left uncommitted: committing is the caller's), render::GlContextError without a GL context.
OverlayReport overlayRecording(const OverlayInputs& inputs, const OverlayOptions& options, FrameSink* sink,
                               const std::function<void(const OverlayProgress&)>& progress = {});

/// Where a run's results are written (empty: not written) and how errors name them ("-o", ...).
struct OverlayOutputs {
  std::string video;          ///< .mp4, .mkv or .avi, written by the VideoSink
  std::string png_dir;        ///< the VideoSink's PNG folder (named in the report only)
  std::string report;         ///< .json: the report with every frame's record
  std::string contact_sheet;  ///< .png: OverlayReport::contact_sheet
  std::string video_option = "-o", report_option = "--report", contact_sheet_option = "--contact-sheet";
  std::string frames_option = "--frames";  ///< named when no frame was drawn for the contact sheet
  std::string timeline;                    ///< .png: drawTimeline of the run (timeline.hpp)
  std::string timeline_option = "--timeline";
  std::string timeline_title;  ///< its caption (e.g. the recording's name)
};
/// Checks the outputs before a run: each one's extension and folder (checkOutputPath), and that
/// neither the video nor the report is one of `inputs` (sameFile: no output may replace an input).
/// Throws OutputError "OPTION PATH: problem".
void checkOverlayOutputs(const OverlayOutputs& outputs, std::span<const std::string> inputs);
/// After a run: writes the contact sheet and the timeline, commits `sink`, writes the report (each staged, in that
/// order) and returns the report (reportJson with frames) naming the files written under "video",
/// "png_dir", "contact_sheet" and "timeline". Throws OutputError (e.g. a contact sheet with no frame drawn).
nlohmann::json writeOverlayOutputs(const OverlayOutputs& outputs, const OverlayReport& report, const Model& model,
                                   VideoSink& sink);
/// The report as JSON (the format of `kccd overlay --report`, docs/formats.md section 9): the
/// summary, and with `with_frames` the per-frame records.
nlohmann::json reportJson(const OverlayReport& report, const Model& model, bool with_frames);

}  // namespace kccd::overlay
