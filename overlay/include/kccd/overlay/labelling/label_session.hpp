// A labelling session (`kccd calib label`): the frames to label, each frame's labels document as
// the page edits it, the candidates a person picks targets from, and the pose solved live from
// whatever is labelled, with the model's volumes at that pose. What the page's HTTP API serves,
// without the HTTP: every call is a library call, and the files it may write are fixed when the
// session is made.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/calib/pose.hpp"
#include "kccd/calib/tag_layout.hpp"
#include "kccd/model.hpp"
#include "kccd/overlay/calibration/calib_refine.hpp"

namespace kccd::overlay {

/// One frame to label.
struct LabelFrame {
  std::string name;                          ///< names the picture (an image file, or "video.mkv#12")
  cv::Mat bgr;                               ///< the picture, 8-bit BGR, the camera's size
  std::optional<std::vector<double>> state;  ///< the robot's state in it (places body labels, draws the volumes)
  std::string labels_path;  ///< its labels file: read when it exists; with PATH.bak the only files written for it
};

/// What a session is made of.
struct LabelSessionInputs {
  calib::Camera intrinsics;              ///< the lens; the pose is what the session solves
  std::string intrinsics_name;           ///< names the camera file in messages
  std::vector<LabelFrame> frames;        ///< at least one
  std::optional<calib::TagLayout> tags;  ///< detected tags it places are points too
  const Model* model = nullptr;          ///< places body labels, draws the volumes (must outlive the session)
  calib::PoseOptions pose;               ///< as `kccd calib` takes them
  std::string camera_output;             ///< the camera file save() writes when solved; empty: none
  int corners = 40;                      ///< strong corners offered per frame
  /// Robot masks, one per frame (CV_8UC1 of the camera's size, non-zero = robot), or none: with
  /// them the page can snap the pose to the robot (setSnap). Every frame then needs a state.
  std::vector<cv::Mat> masks;
  std::vector<std::string> mask_names;  ///< one per mask, as messages name them
  std::vector<int> mask_bodies;         ///< the bodies the masks show (empty: all)
};

/// Where save() wrote.
struct LabelSaved {
  std::vector<std::string> labels;   ///< the labels files written (frames with at least one label)
  std::vector<std::string> backups;  ///< the previous versions kept (LABELS.yaml.bak)
  std::string camera;                ///< the camera file written; empty: none (no -o, or not solved)
};

/// The session. Not thread-safe: one caller at a time (the HTTP server holds a lock).
class LabelSession {
 public:
  /// Reads each frame's labels file when it exists, finds every frame's candidates and solves.
  /// Throws std::invalid_argument without frames; calib::LabelsError for a labels file that cannot
  /// be used; CalibInputError, calib::ImageError or calib::TagDetectionError as
  /// gatherCorrespondences does for inputs that do not fit together.
  explicit LabelSession(LabelSessionInputs inputs);
  ~LabelSession();
  LabelSession(const LabelSession&) = delete;
  LabelSession& operator=(const LabelSession&) = delete;

  /// Everything the page starts from: frames (index, image URL, width, height, state, labels),
  /// `labels` (frame 0's document), candidates (tags, corners, model_points of frame 0; each frame
  /// has its own under frames[i].candidates), bodies (name, frame, world_fixed, points), solve,
  /// revision, dirty.
  nlohmann::json session() const;

  /// The current solve, as `kccd calib --json` reports it, plus `rms_px` and `revision`.
  nlohmann::json solve() const { return solve_json_; }

  /// Replaces frame `frame`'s labels document and solves again; returns solve(). A document that
  /// cannot be used throws calib::LabelsError or CalibInputError with the message `kccd calib`
  /// prints for the same labels saved, and nothing changes. std::out_of_range for a bad frame.
  /// An accepted document with labels is autosaved to the frame's LABELS.yaml.bak (which then
  /// holds the unsaved edits; after save() it holds the version before). A session started where
  /// LABELS.yaml.bak is newer than LABELS.yaml and differs offers it as frames[i].recovered.
  nlohmann::json putLabels(std::size_t frame, const nlohmann::json& document);

  /// Snaps the pose to the robot masks (on) or goes back to the points' solve (off), then solves
  /// again; returns solve(). While on, every solve is refined to the masks as `kccd calib --masks`
  /// refines it (from the points' solve, or a rough pose from 4 or more points; with fewer,
  /// solve()'s snap.message says so and the points' solve stands), solve() carries
  /// `refinement` (refinementJson) and the overlay draws the mask's outline (yellow) and the drawn
  /// robot's (magenta). std::logic_error when the session has no masks.
  nlohmann::json setSnap(bool on);

  /// Frame `frame`'s picture as PNG bytes. std::out_of_range for a bad frame.
  const std::vector<unsigned char>& framePng(std::size_t frame) const;

  /// The model's volumes at frame `frame`'s state as the current estimate sees them: an RGBA PNG
  /// of the frame's size, transparent where there are none (not solved, no model or no state).
  /// Drawn once per revision. Throws render::GlContextError when no GL context can be made.
  const std::vector<unsigned char>& overlayPng(std::size_t frame);

  /// What the volumes show at stored pixel (u, v) of frame `frame` at the current estimate:
  /// `{"body": name or null, "points": [that body's model points, nearest in the image first, each
  /// with "distance_px"], "revision"}`. The body is null where no volume is drawn there, or none
  /// is drawn (not solved, no model or no state). std::out_of_range for a bad frame.
  nlohmann::json pick(std::size_t frame, double u, double v);

  /// Writes every frame's labels (frames without labels are left alone), each file under a
  /// temporary name then renamed, its previous version kept as PATH.bak, and the camera file when
  /// one was asked for and the pose is solved. Not dirty afterwards.
  LabelSaved save();

  std::size_t frameCount() const;             ///< the frames of the session
  int revision() const { return revision_; }  ///< counts the accepted label edits and snap changes
  bool dirty() const { return dirty_; }       ///< edits not saved yet

 private:
  struct Frame;
  void resolve();
  nlohmann::json modelPoints(std::size_t frame) const;
  LabelSessionInputs in_;
  std::vector<Frame> frames_;
  nlohmann::json solve_json_;
  std::optional<calib::Camera> solved_;
  bool snap_ = false;
  std::optional<Refinement> refinement_;  ///< the last solve's refinement while snapping
  int revision_ = 0;
  bool dirty_ = false;
};

}  // namespace kccd::overlay
