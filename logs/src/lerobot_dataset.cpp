#include "kccd/logs/lerobot_dataset.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>

#include <nlohmann/json.hpp>

#include "kccd/file_reader.hpp"
#include "kccd/input_error.hpp"
#include "kccd/logs/parquet_reader.hpp"

namespace kccd::logs {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr std::uintmax_t kMaxMetaBytes = std::uintmax_t{64} << 20;

// A metadata file whole (regular, at most 64 MiB; a FIFO or device refused without blocking). A
// missing one says what the folder was taken for.
std::string readText(const fs::path& path) {
  try {
    return readRegularFile(path.string(), kMaxMetaBytes, "LeRobot metadata file");
  } catch (const FileError& e) {
    if (e.kind() == FileProblem::Missing) throw InputError(path.string() + ": not found (is this a LeRobot dataset?)");
    throw;
  }
}

// The line and column of byte `at` of `text`, as "LINE:COL".
std::string lineColumn(const std::string& text, std::size_t at) {
  at = std::min(at, text.size());
  const std::size_t line = 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + at, '\n'));
  const std::size_t start = text.rfind('\n', at == 0 ? 0 : at - 1);
  return std::to_string(line) + ":" + std::to_string(at - (start == std::string::npos ? 0 : start + 1) + 1);
}

json parseJson(const std::string& text, const std::string& source) {
  try {
    return json::parse(text);
  } catch (const json::parse_error& e) {
    const std::string what = e.what();
    const std::size_t colon = what.find("]: ");
    throw InputError(source + ":" + lineColumn(text, e.byte == 0 ? 0 : e.byte - 1) +
                     ": not JSON: " + printable(colon == std::string::npos ? what : what.substr(colon + 3), 120));
  } catch (const json::exception& e) {  // e.g. a number too large for any type
    const std::string what = e.what();
    const std::size_t bracket = what.find("] ");
    throw InputError(source + ": not readable JSON: " +
                     printable(bracket == std::string::npos ? what : what.substr(bracket + 2), 120));
  }
}

// A value as messages quote it: a scalar's text, or what kind of container it is (never dumped:
// dumping is recursive, and a file may nest deeply).
std::string quoted(const json& j) {
  if (j.is_array()) return "an array";
  if (j.is_object()) return "an object";
  return printable(j.dump(), 40);
}

std::int64_t integerOf(const json& j, const std::string& source, const std::string& field) {
  if (j.is_number_integer()) return j.get<std::int64_t>();
  if (j.is_number_float()) {
    const double d = j.get<double>();
    if (std::isfinite(d) && d == std::floor(d) && std::fabs(d) < 9e15) return static_cast<std::int64_t>(d);
  }
  throw InputError(source + ": " + field + ": expected an integer, got " + quoted(j));
}

double numberOf(const json& j, const std::string& source, const std::string& field) {
  if (j.is_number() && std::isfinite(j.get<double>())) return j.get<double>();
  throw InputError(source + ": " + field + ": expected a number, got " + quoted(j));
}

std::string stringOf(const json& j, const std::string& source, const std::string& field) {
  if (j.is_string()) return j.get<std::string>();
  throw InputError(source + ": " + field + ": expected a string, got " + quoted(j));
}

// Feature names as datasets write them: a list, nested lists, or {"motors": [...]}: every string.
void flattenNames(const json& j, std::vector<std::string>& out, int depth = 0) {
  if (depth > 8) return;
  if (j.is_string()) out.push_back(j.get<std::string>());
  if (j.is_array())
    for (const json& e : j) flattenNames(e, out, depth + 1);
  if (j.is_object())
    for (const auto& [k, v] : j.items()) flattenNames(v, out, depth + 1);
}

LerobotFeature readFeature(const std::string& key, const json& f, const std::string& source) {
  const std::string at = "features." + printable(key, 60);
  if (!f.is_object()) throw InputError(source + ": " + at + ": expected an object");
  LerobotFeature out;
  out.key = key;
  out.dtype = f.contains("dtype") ? stringOf(f["dtype"], source, at + ".dtype") : "";
  if (f.contains("shape") && f["shape"].is_array())
    for (const json& s : f["shape"]) out.shape.push_back(integerOf(s, source, at + ".shape"));
  if (f.contains("names")) flattenNames(f["names"], out.names);
  const json* info = f.contains("info") && f["info"].is_object()               ? &f["info"]
                     : f.contains("video_info") && f["video_info"].is_object() ? &f["video_info"]
                                                                               : nullptr;
  if (info) {
    const auto text = [&](const char* k) {
      return info->contains(k) && (*info)[k].is_string() ? (*info)[k].get<std::string>() : std::string();
    };
    const auto number = [&](const char* k) {
      return info->contains(k) && (*info)[k].is_number() ? (*info)[k].get<double>() : 0.0;
    };
    out.codec = text("video.codec");
    out.pix_fmt = text("video.pix_fmt");
    out.width = static_cast<int>(std::clamp(number("video.width"), 0.0, 1e6));
    out.height = static_cast<int>(std::clamp(number("video.height"), 0.0, 1e6));
    out.fps = std::clamp(number("video.fps"), 0.0, 1e6);
  }
  if (out.isCamera() && (out.width == 0 || out.height == 0) && out.shape.size() == 3) {
    // shape [height, width, channels] (or [channels, height, width]): by the names when given.
    const bool chw = out.names.size() == 3 && out.names[0] == "channels";
    out.height = static_cast<int>(std::clamp<std::int64_t>(out.shape[chw ? 1 : 0], 0, 1000000));
    out.width = static_cast<int>(std::clamp<std::int64_t>(out.shape[chw ? 2 : 1], 0, 1000000));
  }
  return out;
}

void addTask(LerobotDataset& d, const std::string& task) {
  if (std::find(d.tasks.begin(), d.tasks.end(), task) == d.tasks.end()) d.tasks.push_back(task);
}

void readInfo(LerobotDataset& d, const fs::path& root) {
  const fs::path file = root / "meta" / "info.json";
  const std::string source = file.string();
  const json info = parseJson(readText(file), source);
  if (!info.is_object()) throw InputError(source + ": expected a JSON object");
  if (!info.contains("codebase_version"))
    throw InputError(source + ": codebase_version: missing (LeRobot datasets v2.0, v2.1 and v3.0 are read)");
  d.version = stringOf(info["codebase_version"], source, "codebase_version");
  if (d.version.rfind("v2", 0) != 0 && d.version.rfind("v3", 0) != 0)
    throw InputError(source + ": codebase_version: '" + printable(d.version, 20) +
                     "' is not read (LeRobot datasets v2.0, v2.1 and v3.0 are)");
  if (!info.contains("fps")) throw InputError(source + ": fps: missing");
  d.fps = numberOf(info["fps"], source, "fps");
  if (!(d.fps > 0 && d.fps <= 1e6))
    throw InputError(source + ": fps: must be in (0, 1e6], got " + messageNumber(d.fps));
  if (info.contains("robot_type") && info["robot_type"].is_string()) d.robot_type = info["robot_type"];
  if (info.contains("total_episodes")) d.total_episodes = integerOf(info["total_episodes"], source, "total_episodes");
  if (info.contains("total_frames")) d.total_frames = integerOf(info["total_frames"], source, "total_frames");
  if (info.contains("chunks_size")) d.chunks_size = integerOf(info["chunks_size"], source, "chunks_size");
  if (d.chunks_size <= 0) throw InputError(source + ": chunks_size: must be positive");
  const bool v3 = d.isV3();
  d.data_path = info.contains("data_path") ? stringOf(info["data_path"], source, "data_path")
                : v3                       ? "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
                                           : "data/chunk-{episode_chunk:03d}/episode_{episode_index:06d}.parquet";
  d.video_path = info.contains("video_path") && info["video_path"].is_string() ? info["video_path"].get<std::string>()
                 : v3 ? "videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4"
                      : "videos/chunk-{episode_chunk:03d}/{video_key}/episode_{episode_index:06d}.mp4";
  if (!info.contains("features") || !info["features"].is_object()) throw InputError(source + ": features: missing");
  for (const auto& [key, f] : info["features"].items()) d.features.push_back(readFeature(key, f, source));
}

// v2.x: meta/episodes.jsonl, one object per line.
void readEpisodesJsonl(LerobotDataset& d, const fs::path& root) {
  const fs::path file = root / "meta" / "episodes.jsonl";
  const std::string text = readText(file);
  std::size_t start = 0, line = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    ++line;
    std::string row = text.substr(start, end - start);
    start = end + 1;
    if (!row.empty() && row.back() == '\r') row.pop_back();
    if (row.find_first_not_of(" \t") == std::string::npos) continue;
    const std::string source = file.string() + ":" + std::to_string(line);
    json j;
    try {
      j = json::parse(row);
    } catch (const json::parse_error& e) {
      throw InputError(source + ":" + std::to_string(e.byte) + ": not JSON");
    } catch (const json::exception&) {  // e.g. a number too large for any type
      throw InputError(source + ": not readable JSON (a number out of range)");
    }
    if (!j.is_object() || !j.contains("episode_index") || !j.contains("length"))
      throw InputError(source + ": expected an object with episode_index and length");
    LerobotEpisode e;
    e.index = integerOf(j["episode_index"], source, "episode_index");
    e.length = integerOf(j["length"], source, "length");
    if (e.index < 0 || e.length < 0) throw InputError(source + ": episode_index and length must not be negative");
    if (j.contains("tasks") && j["tasks"].is_array())
      for (const json& t : j["tasks"])
        if (t.is_string()) {
          e.tasks.push_back(t.get<std::string>());
          addTask(d, e.tasks.back());
        }
    d.episodes.push_back(std::move(e));
  }
}

// One integer per row of column `name` (0 for a null); none when the table lacks it.
std::vector<std::int64_t> integers(const ParquetFile& table, const std::string& name) {
  std::vector<std::int64_t> out;
  if (!table.hasColumn(name)) return out;
  const ParquetColumn c = table.read(name);
  out.reserve(c.rows());
  for (std::size_t r = 0; r < c.rows(); ++r) {
    const double v = c.rowStart[r + 1] > c.rowStart[r] && !c.isBytes ? c.numbers[c.rowStart[r]] : 0.0;
    out.push_back(std::isfinite(v) ? static_cast<std::int64_t>(v) : 0);
  }
  return out;
}

std::vector<double> reals(const ParquetFile& table, const std::string& name) {
  std::vector<double> out;
  if (!table.hasColumn(name)) return out;
  const ParquetColumn c = table.read(name);
  for (std::size_t r = 0; r < c.rows(); ++r)
    out.push_back(c.rowStart[r + 1] > c.rowStart[r] && !c.isBytes ? c.numbers[c.rowStart[r]] : std::nan(""));
  return out;
}

// v3.0: meta/episodes/chunk-*/file-*.parquet, one row per episode.
void readEpisodesTables(LerobotDataset& d, const fs::path& root) {
  const fs::path dir = root / "meta" / "episodes";
  std::vector<fs::path> files;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    if (it->path().extension() == ".parquet") files.push_back(it->path());
  if (files.empty()) throw InputError(dir.string() + ": no episode table (*.parquet) in it (a v3.0 dataset has them)");
  std::sort(files.begin(), files.end());
  const std::vector<std::string> cameras = d.cameras();
  for (const fs::path& file : files) {
    const ParquetFile table(file.string());
    if (!table.hasColumn("episode_index") || !table.hasColumn("length"))
      throw InputError(file.string() + ": no episode_index or length column (not a LeRobot episodes table)");
    const std::vector<std::int64_t> index = integers(table, "episode_index"), length = integers(table, "length"),
                                    chunk = integers(table, "data/chunk_index"),
                                    data_file = integers(table, "data/file_index"),
                                    from = integers(table, "dataset_from_index"),
                                    to = integers(table, "dataset_to_index");
    std::optional<ParquetColumn> tasks;
    if (table.hasColumn("tasks")) tasks = table.read("tasks");
    const std::size_t n = index.size();
    for (std::size_t r = 0; r < n; ++r) {
      LerobotEpisode e;
      e.index = index[r];
      e.length = r < length.size() ? length[r] : 0;
      e.data_chunk = r < chunk.size() ? chunk[r] : 0;
      e.data_file = r < data_file.size() ? data_file[r] : 0;
      e.from_index = r < from.size() ? from[r] : -1;
      e.to_index = r < to.size() ? to[r] : -1;
      if (tasks && tasks->isBytes)
        for (std::size_t k = tasks->rowStart[r]; k < tasks->rowStart[r + 1]; ++k) {
          e.tasks.push_back(tasks->bytes[k]);
          addTask(d, tasks->bytes[k]);
        }
      d.episodes.push_back(std::move(e));
    }
    for (const std::string& key : cameras) {
      const std::string p = "videos/" + key + "/";
      if (!table.hasColumn(p + "chunk_index")) continue;
      const std::vector<std::int64_t> vchunk = integers(table, p + "chunk_index"),
                                      vfile = integers(table, p + "file_index");
      const std::vector<double> vfrom = reals(table, p + "from_timestamp"), vto = reals(table, p + "to_timestamp");
      for (std::size_t r = 0; r < n; ++r) {
        LerobotEpisode& e = d.episodes[d.episodes.size() - n + r];
        LerobotVideoSpan span;
        span.file = (root / expandLerobotPath(d.video_path, {{"video_key", key}},
                                              {{"chunk_index", r < vchunk.size() ? vchunk[r] : 0},
                                               {"file_index", r < vfile.size() ? vfile[r] : 0}},
                                              root.string() + "/meta/info.json: video_path"))
                        .string();
        span.from = r < vfrom.size() && std::isfinite(vfrom[r]) ? vfrom[r] : 0.0;
        span.to = r < vto.size() && std::isfinite(vto[r]) ? vto[r] : -1.0;
        e.videos[key] = span;
      }
    }
  }
}

}  // namespace

std::string expandLerobotPath(const std::string& pattern, const std::map<std::string, std::string>& strings,
                              const std::map<std::string, std::int64_t>& numbers, const std::string& source) {
  std::string out;
  for (std::size_t i = 0; i < pattern.size(); ++i) {
    if (pattern[i] != '{') {
      out += pattern[i];
      continue;
    }
    const std::size_t close = pattern.find('}', i);
    if (close == std::string::npos) throw InputError(source + ": '{' without '}' in '" + printable(pattern) + "'");
    const std::string field = pattern.substr(i + 1, close - i - 1);
    const std::size_t colon = field.find(':');
    const std::string name = field.substr(0, colon), spec = colon == std::string::npos ? "" : field.substr(colon + 1);
    if (const auto s = strings.find(name); s != strings.end() && spec.empty()) {
      out += s->second;
    } else if (const auto n = numbers.find(name); n != numbers.end()) {
      // "" or "0Nd" (zero-padded to N digits) or "d".
      std::size_t width = 0;
      if (!spec.empty()) {
        if (spec.back() != 'd' || (spec.size() > 1 && spec[0] != '0') || spec.size() > 4 ||
            !std::all_of(spec.begin(), spec.end() - 1, [](char c) { return c >= '0' && c <= '9'; }))
          throw InputError(source + ": format '{" + printable(field) + "}' is not read (only {name:0Nd})");
        width = spec.size() > 1 ? static_cast<std::size_t>(std::stoi(spec.substr(0, spec.size() - 1))) : 0;
      }
      std::string digits = std::to_string(n->second < 0 ? -n->second : n->second);
      if (digits.size() < width) digits.insert(0, width - digits.size(), '0');
      out += (n->second < 0 ? "-" : "") + digits;
    } else {
      throw InputError(source + ": '{" + printable(field) + "}' names nothing LeRobot's paths have");
    }
    i = close;
  }
  return out;
}

const LerobotFeature* LerobotDataset::feature(const std::string& key) const {
  for (const LerobotFeature& f : features)
    if (f.key == key) return &f;
  return nullptr;
}

std::vector<std::string> LerobotDataset::cameras() const {
  std::vector<std::string> out;
  for (const LerobotFeature& f : features)
    if (f.isCamera()) out.push_back(f.key);
  return out;
}

const LerobotEpisode& LerobotDataset::episode(std::int64_t index) const {
  for (const LerobotEpisode& e : episodes)
    if (e.index == index) return e;
  std::string range = episodes.empty()
                          ? std::string("none")
                          : std::to_string(episodes.front().index) + " ... " + std::to_string(episodes.back().index);
  throw InputError(root + ": episode " + std::to_string(index) + ": not in the dataset (its episodes: " + range + ")");
}

std::string LerobotDataset::dataFile(const LerobotEpisode& e) const {
  const std::string source = root + "/meta/info.json: data_path";
  const std::string rel =
      isV3() ? expandLerobotPath(data_path, {}, {{"chunk_index", e.data_chunk}, {"file_index", e.data_file}}, source)
             : expandLerobotPath(data_path, {}, {{"episode_chunk", e.index / chunks_size}, {"episode_index", e.index}},
                                 source);
  return (fs::path(root) / rel).string();
}

LerobotVideoSpan LerobotDataset::video(const LerobotEpisode& e, const std::string& key) const {
  if (isV3()) {
    const auto it = e.videos.find(key);
    if (it == e.videos.end())
      throw InputError(root + ": episode " + std::to_string(e.index) + ": the episodes table gives no video of '" +
                       printable(key, 60) + "'");
    return it->second;
  }
  LerobotVideoSpan span;
  span.file =
      (fs::path(root) / expandLerobotPath(video_path, {{"video_key", key}},
                                          {{"episode_chunk", e.index / chunks_size}, {"episode_index", e.index}},
                                          root + "/meta/info.json: video_path"))
          .string();
  return span;
}

LerobotDataset openLerobotDataset(const std::string& dir) {
  LerobotDataset d;
  d.root = dir;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw InputError(dir + ": not a folder (a LeRobot dataset is one)");
  const fs::path root(dir);
  readInfo(d, root);
  if (d.isV3())
    readEpisodesTables(d, root);
  else
    readEpisodesJsonl(d, root);
  std::stable_sort(d.episodes.begin(), d.episodes.end(),
                   [](const LerobotEpisode& a, const LerobotEpisode& b) { return a.index < b.index; });
  for (std::size_t i = 1; i < d.episodes.size(); ++i)
    if (d.episodes[i].index == d.episodes[i - 1].index)
      throw InputError(dir + "/meta: episode " + std::to_string(d.episodes[i].index) + " is listed twice");
  if (d.total_episodes != 0 && d.total_episodes != static_cast<std::int64_t>(d.episodes.size()))
    d.warnings.push_back("meta/info.json says " + std::to_string(d.total_episodes) +
                         " episodes, the episode list has " + std::to_string(d.episodes.size()) + ": the list is read");
  return d;
}

namespace {

// The row groups of `table` that may hold rows of `episode` (by the episode_index statistics), and
// the rows of those groups that do.
struct EpisodeRows {
  std::vector<std::size_t> groups;
  std::vector<std::size_t> rows;  // indices into the groups' rows, in order
};

EpisodeRows findEpisodeRows(const ParquetFile& table, std::int64_t episode, bool shared) {
  EpisodeRows out;
  for (std::size_t g = 0; g < table.rowGroups().size(); ++g) {
    const auto range = shared ? table.integerRange("episode_index", g) : std::nullopt;
    if (!range || (range->first <= episode && episode <= range->second)) out.groups.push_back(g);
  }
  if (!shared || !table.hasColumn("episode_index")) {
    std::size_t n = 0;
    for (const std::size_t g : out.groups) n += static_cast<std::size_t>(table.rowGroups()[g].rows);
    for (std::size_t r = 0; r < n; ++r) out.rows.push_back(r);
    return out;
  }
  const ParquetColumn index = table.read("episode_index", out.groups);
  for (std::size_t r = 0; r < index.rows(); ++r)
    if (index.rowStart[r + 1] > index.rowStart[r] && index.numbers[index.rowStart[r]] == static_cast<double>(episode))
      out.rows.push_back(r);
  return out;
}

std::vector<double> scalarColumn(const ParquetFile& table, const std::string& name, const EpisodeRows& at) {
  const ParquetColumn c = table.read(name, at.groups);
  if (c.isBytes) throw InputError(table.path() + ": column " + name + ": expected numbers, holds bytes");
  std::vector<double> out;
  out.reserve(at.rows.size());
  for (const std::size_t r : at.rows) {
    if (c.rowStart[r + 1] - c.rowStart[r] != 1)
      throw InputError(table.path() + ": column " + name + ", row " + std::to_string(r) + ": expected one value");
    out.push_back(c.numbers[c.rowStart[r]]);
  }
  return out;
}

void checkLength(const LerobotEpisode& e, const std::string& file, std::size_t rows) {
  if (rows == 0)
    throw InputError(file + ": no row of episode " + std::to_string(e.index) + " (the metadata lists " +
                     std::to_string(e.length) + ")");
}

}  // namespace

LerobotRows readLerobotRows(const LerobotDataset& d, std::int64_t episode, const std::string& key) {
  const LerobotEpisode& e = d.episode(episode);
  LerobotRows out;
  out.file = d.dataFile(e);
  const ParquetFile table(out.file);
  const EpisodeRows at = findEpisodeRows(table, episode, d.isV3());
  checkLength(e, out.file, at.rows.size());
  if (!table.hasColumn(key)) {
    std::string have;
    for (const std::string& c : table.columns()) have += (have.empty() ? "" : ", ") + printable(c, 60);
    throw InputError(out.file + ": no column '" + printable(key, 60) + "' (it has: " + have + ")");
  }
  if (!table.hasColumn("timestamp")) throw InputError(out.file + ": no column 'timestamp'");
  out.timestamps = scalarColumn(table, "timestamp", at);
  if (table.hasColumn("frame_index")) {
    for (const double f : scalarColumn(table, "frame_index", at))
      out.frame_index.push_back(static_cast<std::int64_t>(f));
  } else {
    for (std::size_t r = 0; r < at.rows.size(); ++r) out.frame_index.push_back(static_cast<std::int64_t>(r));
  }
  const ParquetColumn c = table.read(key, at.groups);
  if (c.isBytes) throw InputError(out.file + ": column " + key + ": holds bytes, not numbers");
  const std::size_t width = c.rowStart[at.rows.front() + 1] - c.rowStart[at.rows.front()];
  if (width == 0)
    throw InputError(out.file + ": column " + key + ", row " + std::to_string(at.rows.front()) + ": empty");
  out.values.reserve(at.rows.size() * width);
  for (const std::size_t r : at.rows) {
    const std::size_t n = c.rowStart[r + 1] - c.rowStart[r];
    if (n != width)
      throw InputError(out.file + ": column " + key + ", row " + std::to_string(r) + ": " + std::to_string(n) +
                       " values, the first row of the episode has " + std::to_string(width));
    out.values.insert(out.values.end(), c.numbers.begin() + static_cast<std::ptrdiff_t>(c.rowStart[r]),
                      c.numbers.begin() + static_cast<std::ptrdiff_t>(c.rowStart[r + 1]));
  }
  const LerobotFeature* f = d.feature(key);
  if (f && f->names.size() == width) {
    out.names = f->names;
  } else {
    for (std::size_t i = 0; i < width; ++i) out.names.push_back(key + "[" + std::to_string(i) + "]");
  }
  return out;
}

std::vector<std::string> readLerobotImages(const LerobotDataset& d, std::int64_t episode, const std::string& key) {
  const LerobotEpisode& e = d.episode(episode);
  const std::string file = d.dataFile(e);
  const ParquetFile table(file);
  const EpisodeRows at = findEpisodeRows(table, episode, d.isV3());
  checkLength(e, file, at.rows.size());
  const std::string name = table.hasColumn(key + "/bytes") ? key + "/bytes" : key;
  if (!table.hasColumn(name)) throw InputError(file + ": no column '" + printable(key, 60) + "' (an image feature)");
  const ParquetColumn c = table.read(name, at.groups);
  if (!c.isBytes) throw InputError(file + ": column " + name + ": holds numbers, not encoded images");
  std::vector<std::string> out;
  out.reserve(at.rows.size());
  for (const std::size_t r : at.rows) {
    if (c.rowStart[r + 1] - c.rowStart[r] != 1)
      throw InputError(file + ": column " + name + ", row " + std::to_string(r) + ": expected one image");
    out.push_back(c.bytes[c.rowStart[r]]);
  }
  return out;
}

}  // namespace kccd::logs
