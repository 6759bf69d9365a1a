// The golden manifest of `kccd golden` (docs/formats.md): the cases an integrator's CI renders and
// compares, each a model seen by a camera at a state, over a box, or on a recorded frame. Every
// mistake is one InputError `file:line:col: field: problem`.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "kccd/input_error.hpp"
#include "kccd/overlay/golden/golden_compare.hpp"

namespace kccd::overlay {

/// What a case renders and compares.
enum class GoldenOutput { Mask, Colour, Overlay };

/// "mask", "colour" or "overlay".
const char* goldenOutputName(GoldenOutput output);

/// Where a tolerance in force came from, for the report.
struct ToleranceSource {
  std::string mask = "built-in", colour = "built-in", overlay = "built-in";  ///< "built-in", "defaults" or "case"
};

/// One case of the manifest. Paths are as resolved against the manifest's folder.
struct GoldenCase {
  std::string id;     ///< unique; names the golden's folder
  std::string where;  ///< "file:line:col" of the case, for messages
  std::string model, camera;
  std::vector<GoldenOutput> outputs;
  std::vector<double> state;             ///< a configuration (static volumes), or
  std::vector<double> lower, upper;      ///< a box (swept volumes), or
  std::string video, states;             ///< a recorded frame composited, its state from the log, or
  std::string bag;                       ///< a robot log's frame, its state from the log's joint states
  std::string image_topic, joint_topic;  ///< with bag: the topics (empty: the one of the fitting type)
  bool log_time = false;                 ///< with bag: the recorder's times, not the header stamps
  std::string lerobot;                   ///< a LeRobot dataset's episode frame, its state from the episode's row
  long episode = -1;                     ///< with lerobot: the episode_index
  std::string camera_key;                ///< with lerobot: the camera (empty: the only one)
  std::int64_t frame = -1;
  double time_offset = 0.0;  ///< added to the frame's time to get the log's time (s)
  /// Pinhole scale (1..4) of the mask and colour images: finer masks follow the volumes' edges
  /// closer (render::Frame::mask_edge_px).
  double supersample = 1.0;
  MaskTolerance mask;
  ColourTolerance colour, overlay;
  ToleranceSource tolerance_source;
  /// A case on a recorded frame (of a video, a bag or a dataset).
  bool hasVideo() const { return !video.empty() || !bag.empty() || !lerobot.empty(); }
};

/// A manifest: where its goldens live and its cases in order.
struct GoldenManifest {
  std::string path;     ///< the manifest as given
  std::string folder;   ///< the folder relative paths are resolved against
  std::string goldens;  ///< the goldens' folder (resolved)
  std::vector<GoldenCase> cases;
};

/// The largest manifest read (bytes) and the most cases.
inline constexpr std::uintmax_t kMaxManifestBytes = 4u << 20;
inline constexpr std::size_t kMaxGoldenCases = 10000;

/// Parses a manifest's text; `path` names it in messages and gives the folder paths are relative
/// to. Throws InputError. Files are not opened (see loadGoldenManifest).
GoldenManifest parseGoldenManifest(const std::string& text, const std::string& path);

/// Reads and parses the manifest file (regular, at most kMaxManifestBytes). Throws InputError.
GoldenManifest loadGoldenManifest(const std::string& path);

}  // namespace kccd::overlay
