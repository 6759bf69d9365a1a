// LeRobot datasets (https://github.com/huggingface/lerobot) as downloaded to a local folder:
// codebase versions v2.0/v2.1 (meta/info.json, meta/episodes.jsonl, one Parquet table and one video
// per episode) and v3.0 (meta/episodes/*.parquet, many episodes per data and per video file, each
// episode's span of a video given by its from_timestamp). What the format says, read without the
// videos' pixels: the overlay reads the frames (overlay/datasets).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace kccd::logs {

/// One feature of info.json: a column of the data tables, or a camera.
struct LerobotFeature {
  std::string key;    ///< e.g. "observation.state", "observation.images.wrist"
  std::string dtype;  ///< "float32", "int64", "video", "image", ...
  std::vector<std::int64_t> shape;
  std::vector<std::string> names;  ///< flattened (nested lists and {"motors": [...]} both read); may be empty
  // Cameras (dtype "video"): what info.json says of the videos (empty or 0 when it says nothing).
  std::string codec, pix_fmt;
  int width = 0, height = 0;
  double fps = 0.0;
  bool isCamera() const { return dtype == "video" || dtype == "image"; }
};

/// Where one episode's frames of one camera are in a video file.
struct LerobotVideoSpan {
  std::string file;   ///< the video file (may not exist: a dataset downloaded without its videos)
  double from = 0.0;  ///< the episode's first frame's time in the file (s; v3.0, else 0)
  double to = -1.0;   ///< the end of the episode in the file (s; < 0: the file's end)
};

/// One episode as the metadata lists it.
struct LerobotEpisode {
  std::int64_t index = 0;
  std::int64_t length = 0;  ///< rows (frames)
  std::vector<std::string> tasks;
  // v3.0: where its rows and videos are.
  std::int64_t data_chunk = 0, data_file = 0;
  std::int64_t from_index = -1, to_index = -1;     ///< its rows' global `index` range [from, to)
  std::map<std::string, LerobotVideoSpan> videos;  ///< per camera key
};

/// A dataset's metadata.
struct LerobotDataset {
  std::string root;     ///< the folder given
  std::string version;  ///< codebase_version, e.g. "v2.1"
  std::string robot_type;
  double fps = 0.0;
  std::int64_t total_episodes = 0, total_frames = 0, chunks_size = 1000;
  std::string data_path, video_path;     ///< info.json's path templates
  std::vector<LerobotFeature> features;  ///< in info.json's order
  std::vector<LerobotEpisode> episodes;  ///< in index order
  std::vector<std::string> tasks;        ///< every task named, in first-use order
  std::vector<std::string> warnings;     ///< what does not match the format, and what was done

  bool isV3() const { return version.rfind("v3", 0) == 0; }
  /// The feature named `key`, or null.
  const LerobotFeature* feature(const std::string& key) const;
  /// The cameras' keys (video and image features), in info.json's order.
  std::vector<std::string> cameras() const;
  /// The episode with index `index`; throws InputError "DIR: episode N: ..." naming the range.
  const LerobotEpisode& episode(std::int64_t index) const;
  /// The Parquet file holding the episode's rows.
  std::string dataFile(const LerobotEpisode& episode) const;
  /// Where the episode's frames of camera `key` are (a video feature).
  LerobotVideoSpan video(const LerobotEpisode& episode, const std::string& key) const;
};

/// Reads `dir`'s metadata. Throws InputError naming the file and place (meta/info.json, a line of
/// meta/episodes.jsonl, a v3.0 episodes table) for anything that cannot be read; what can be read
/// despite straying from the format is read, with one warning each.
LerobotDataset openLerobotDataset(const std::string& dir);

/// One episode's rows: their times, frame indices and a vector feature's values.
struct LerobotRows {
  std::string file;                       ///< the Parquet file read
  std::vector<double> timestamps;         ///< per row, seconds from the episode's start (`timestamp`)
  std::vector<std::int64_t> frame_index;  ///< per row (`frame_index`; the row's position when absent)
  std::vector<std::string> names;         ///< the feature's value names (its `names`, else KEY[i])
  std::vector<double> values;             ///< rows x names.size(), row-major
  std::size_t rows() const { return timestamps.size(); }
};

/// Reads episode `episode`'s rows of the vector feature `key` (e.g. "observation.state"): only
/// its row groups and these columns. Throws InputError naming the file for a missing column, rows
/// of different lengths, or a table that holds fewer rows of the episode than the metadata says.
LerobotRows readLerobotRows(const LerobotDataset& dataset, std::int64_t episode, const std::string& key);

/// The encoded images (PNG or JPEG bytes) of an image feature `key` stored in the episode's
/// Parquet rows, one per row. Throws InputError.
std::vector<std::string> readLerobotImages(const LerobotDataset& dataset, std::int64_t episode, const std::string& key);

/// Expands a Python format template as LeRobot's paths use it ("{episode_index:06d}", "{video_key}").
/// Throws InputError naming `source` for a field not in `values` or a format spec it cannot follow.
std::string expandLerobotPath(const std::string& pattern, const std::map<std::string, std::string>& strings,
                              const std::map<std::string, std::int64_t>& numbers, const std::string& source);

}  // namespace kccd::logs
