// The model as the camera sees it: a model's volumes (and its visual geometry, when loaded) at a
// state or swept over a box, coloured by a query's answer or by statuses given, drawn for one
// camera. What `kccd render`, the overlay's frames, the synthetic recordings and the calibration
// check image draw.
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/checker.hpp"
#include "kccd/model.hpp"
#include "kccd/render/projection.hpp"
#include "kccd/render/render_types.hpp"
#include "kccd/render/renderer.hpp"
#include "kccd/render/visuals.hpp"
#include "kccd/safety_status.hpp"

namespace kccd::render {

/// What a ModelView draws: where the model is, where its colours come from, and which images.
/// The views must stay valid during the draw.
struct ModelViewRequest {
  /// The configuration (one value per state value): the static volumes and the visuals are placed
  /// at it. Empty, with no box either: no state is known; only the bodies fixed in the world are
  /// drawn (grey) and nothing is queried.
  std::span<const double> state;
  /// A box (one interval per state value, `lower` and `upper` alike long): the volumes swept over
  /// it, queried on it; the visuals stay at `state`. Empty: the box is `state` itself.
  std::span<const double> lower, upper;
  /// Per body, the statuses to colour by instead of the query's (e.g. all colliding when no
  /// braking box could be had, all NoState for grey); empty: the query's (see bodyStatus).
  std::span<const SafetyStatus> status;
  /// Per body, a BGR fill colour overriding the status colour (see Volume::colour); empty: none.
  std::span<const cv::Scalar> colours;
  double radius_scale = 1.0;  ///< the volumes' radii times this (e.g. below 1 for a robot's look)
  bool tight_volumes = true;  ///< QueryOptions::tight_volumes of the query (display volumes)
  bool volumes = true;        ///< draw the bodies' volumes
  bool visuals = false;       ///< draw the loaded visuals too (after the volumes), when a state is given
  bool colour = true;         ///< make the colour layer (Frame::bgra)
  bool mask = true;           ///< make the label mask (Frame::mask, Frame::pixels); neither: query only, no images
  Style style;                ///< the colour layer's look: labels, legend, shaded, ...
  /// When set (with `colour` and without `mask`): the colour layer is composited straight onto
  /// this CV_8UC3 camera image (see Renderer::renderOnto) instead of made as Frame::bgra.
  cv::Mat* onto = nullptr;
};

/// What a ModelView drew: the images with each volume's visibility and pixels, and per body the
/// status it was coloured by.
struct ModelFrame {
  /// The renderer's frame. With ModelViewRequest::volumes, volume i is body i; the visuals follow
  /// from `first_visual` on.
  Frame images;
  std::size_t first_visual = 0;      ///< index in `images` of the first visual
  std::vector<SafetyStatus> status;  ///< per body, the status it is coloured by
  /// Per body the smallest distance bound among its pairs (+inf: in none); empty without a query.
  std::vector<double> distances;
  /// The query's answer (its pairs view the checker: valid until the next draw); none without a state.
  std::optional<QueryResult> query;
  double query_seconds = 0.0;  ///< the query and the volumes for drawing (images.times has the drawing's)
  /// The request was the last one's, bit for bit, drawn onto an image: the last query's answer
  /// and layer were put onto this image (Renderer::renderOntoAgain) instead of being made again.
  bool reused = false;
};

/// Draws one model for one camera; owns the checker, the renderer (a GL context: one view per
/// thread) and the model's loaded visuals.
/// The model frame a camera is fixed to (Camera::frame): a joint's name, or a body's or link's (its
/// frame); kWorld for an empty name or "world". Throws CameraError "SOURCE: frame: ..." naming the
/// joints and bodies when the model has no such frame.
int cameraFrame(const Model& model, const Camera& camera, const std::string& source = "camera");

class ModelView {
 public:
  /// For `model` (which must outlive the view) seen by `camera`; throws what Renderer's constructor
  /// throws (GlContextError, CameraError) and cameraFrame's CameraError. `visuals` (see
  /// loadVisuals) are drawn when asked. A camera fixed to a frame of the model sees from where that
  /// frame is at the request's state (the box's middle when only a box is given); with no state
  /// nothing can be placed and nothing is drawn.
  ModelView(const Model& model, const Camera& camera, const RenderOptions& options = {},
            std::vector<LoadedVisual> visuals = {});
  /// The same with the colour pass's projection made once elsewhere (see Renderer).
  ModelView(const Model& model, const Projection& projection, const RenderOptions& options,
            std::vector<LoadedVisual> visuals = {});
  ModelView(const ModelView&) = delete;
  ModelView& operator=(const ModelView&) = delete;

  /// Queries the box (a Distances query from a reset table, so the answer depends on the request
  /// alone), places and colours the volumes and draws them. A request drawn onto an image that
  /// equals the last such request bit for bit (state, box, statuses, colours, style, flags) reuses
  /// the last answer and layer (ModelFrame::reused): the same pixels and answer, without the query
  /// and the drawing (a robot standing still). Throws std::invalid_argument for statuses or
  /// colours not one per body, or more than 255 volumes and visuals.
  ModelFrame draw(const ModelViewRequest& request);

  /// The model drawn.
  const Model& model() const { return model_; }
  /// The renderer (its projections, GL renderer name and mesh cache).
  const Renderer& renderer() const { return renderer_; }

 private:
  // Moves `volumes` from the world into the camera's frame at the request's state; false when the
  // state (or box) cannot place it.
  bool placeInCameraFrame(const ModelViewRequest& request, std::vector<Volume>& volumes) const;

  const Model& model_;
  Checker checker_;
  Renderer renderer_;
  std::vector<LoadedVisual> visuals_;
  int camera_frame_ = kWorld;  // cameraFrame(): where the camera is fixed
  // The last request drawn onto an image, and what it gave (no images): reused when the next is equal.
  struct LastOnto {
    std::vector<double> state, lower, upper;
    std::vector<SafetyStatus> status;
    std::vector<cv::Scalar> colours;
    double radius_scale = 1.0;
    bool tight_volumes = true, volumes = true, visuals = false;
    Style style;
    ModelFrame frame;
  };
  std::optional<LastOnto> last_onto_;
  bool sameAsLastOnto(const ModelViewRequest& request) const;
  ModelFrame drawAnew(const ModelViewRequest& request);
};

}  // namespace kccd::render
