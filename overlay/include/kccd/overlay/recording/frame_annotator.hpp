// One video frame annotated: its time -> the logged state -> the library's query -> a safety status
// -> the collision volumes rendered from the camera -> composited onto the frame.
#pragma once

#include <array>
#include <cstddef>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "kccd/braking.hpp"
#include "kccd/checker.hpp"
#include "kccd/render/model_view.hpp"
#include "kccd/render/projection.hpp"
#include "kccd/render/visuals.hpp"
#include "kccd/safety_status.hpp"
#include "kccd/state_log.hpp"

namespace kccd::overlay {

/// Where a frame's time went, seconds of wall time on the thread that did each stage (they
/// overlap across threads: decoding, annotating and encoding run side by side).
struct StageTimes {
  double decode = 0.0;     ///< the video's frame into BGR
  double state = 0.0;      ///< the state (and braking box) at the frame's time
  double query = 0.0;      ///< the distance query and the volumes to draw
  double render = 0.0;     ///< meshes, outlines and GL drawing
  double read_back = 0.0;  ///< the drawn pixels out of GL
  double warp = 0.0;       ///< the lens warp, straight alpha and the layer blended onto the frame
  double composite = 0.0;  ///< the status line and the legend (FrameDecoration, on the writing thread)
  double encode = 0.0;     ///< the frame handed to the output (encoded)
  StageTimes& operator+=(const StageTimes& o);
};

/// What a run says about one input frame.
struct FrameRecord {
  double time = 0.0;                    ///< on the video's clock (index / fps, or the frame-times file)
  StateMatch match = StateMatch::None;  ///< how the state log gave the frame's state
  SafetyStatus status = SafetyStatus::NoState;
  Status query = Status::Ok;    ///< the query's own status
  bool braking_failed = false;  ///< a non-finite position or velocity: no braking box (unsafe)
  bool not_finite = false;      ///< a volume could not be drawn (overflow): unsafe
  double min_distance = std::numeric_limits<double>::quiet_NaN();  ///< the bound, NaN without one
  std::vector<std::array<int, 2>> pairs;  ///< body pairs within the margin (model body indices)
  std::vector<double> values;             ///< the state used (empty without one)
  bool selected = false;                  ///< drawn (and handed to the sink)
  bool written = false;                   ///< handed to a sink that keeps frames
  bool reused = false;  ///< drawn by reusing the annotator's last answer and layer (the same state, bit for bit)
  StageTimes times;     ///< where its time went
  std::optional<double> mask_iou;  ///< agreement with the frame's robot mask (OverlayInputs::masks), when it has one
  /// Per AnnotatorSettings::legend_corners box, the picture's pixels the volumes changed (when selected).
  std::array<int, 4> legend_cover{};
  /// True when the frame's check cannot be trusted: treat the robot as unsafe.
  bool unsafe() const { return query != Status::Ok || braking_failed || not_finite; }
  /// The report's "query_status": "no_braking_box", "volume_not_finite" or the query's status word.
  const char* queryStatusText() const;
};

/// Fills `record` from the query's answer for its state or box: the query's status, the bound (none
/// for an unsafe status or without a braking box, `box_ok` false), the body pairs within the
/// margin (with `pairs`) and the safety status (colliding without a braking box). What the
/// overlay and the check job say of a frame or a sample.
void recordAnswer(const Model& model, const QueryResult& answer, bool box_ok, FrameRecord& record, bool pairs = true);

/// The links (Body::linkName) of body pairs, each link pair once, in order: the pieces of a
/// concave link are one link to the user.
std::vector<std::array<std::string, 2>> linkPairs(const Model& model, const std::vector<std::array<int, 2>>& pairs);

/// How every frame of a run is checked and drawn.
struct AnnotatorSettings {
  double time_offset = 0.0;            ///< added to a frame's time to get the state log's time (s)
  double max_gap = 0.0;                ///< no state when no two samples this close bracket the time (s)
  bool swept = false;                  ///< braking-interval swept volumes instead of the static ones
  std::vector<BrakingParams> braking;  ///< per state value, with `swept`
  /// Boxes (at most 4) under which FrameRecord::legend_cover counts the pixels the volumes change.
  std::vector<cv::Rect> legend_corners;
};

/// What every annotator of a run reads; it must outlive them.
struct AnnotatorScene {
  const Model& model;
  const StateLog& log;
  const render::Projection& projection;  ///< made once per run, copied by each annotator's renderer
  render::RenderOptions render_options;
  std::span<const render::LoadedVisual> visuals;  ///< drawn at the logged state when not empty
  AnnotatorSettings settings;
};

/// Checks and draws frames; one per thread, since its renderer's GL context is current on the
/// thread that made it. Allocates per frame only for the drawing, never in the query.
class FrameAnnotator {
 public:
  /// Makes its model view (checker, renderer with its GL context, visuals). Throws render::GlContextError.
  explicit FrameAnnotator(const AnnotatorScene& scene);
  ~FrameAnnotator();
  FrameAnnotator(const FrameAnnotator&) = delete;
  FrameAnnotator& operator=(const FrameAnnotator&) = delete;

  /// Fills `record` from its time (state, query, status) and, when it is selected, composites
  /// the volumes onto `bgr` (8-bit BGR, the camera's size) and counts the legend's cover.
  void annotate(cv::Mat& bgr, FrameRecord& record);

 private:
  const AnnotatorScene& scene_;
  render::ModelView view_;
  std::vector<double> q_, v_, lo_, hi_;
  std::vector<SafetyStatus> all_colliding_;
  std::vector<cv::Mat> under_legend_;  // the picture under each legend corner before drawing
  cv::Mat difference_, unchanged_;     // their comparison after drawing
};

}  // namespace kccd::overlay
