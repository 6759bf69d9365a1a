// libFuzzer target: a LeRobot dataset's metadata (kccd::logs::openLerobotDataset): the input up to
// its first line "---" is meta/info.json, the rest meta/episodes.jsonl. Any input must open or be
// rejected with kccd::InputError on one line naming the dataset's folder; an opened dataset keeps
// its promises: episodes in strictly increasing index order, a positive finite fps, and every
// episode's data and video paths expand (or are refused the same way).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <string_view>

#include "fuzz_support.hpp"
#include "kccd/input_error.hpp"
#include "kccd/logs/lerobot_dataset.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const std::size_t cut = text.find("\n---\n");
  const std::string_view info = text.substr(0, cut),
                         episodes = cut == std::string_view::npos ? "" : text.substr(cut + 5);
  const std::string info_path = kccd::fuzz::writeInput("fuzz_lerobot", "info.json",
                                                       reinterpret_cast<const std::uint8_t*>(info.data()), info.size());
  const std::filesystem::path root = std::filesystem::path(info_path).parent_path() / "dataset";
  std::filesystem::create_directories(root / "meta");
  std::filesystem::rename(info_path, root / "meta" / "info.json");
  const std::string jsonl = kccd::fuzz::writeInput(
      "fuzz_lerobot", "episodes.jsonl", reinterpret_cast<const std::uint8_t*>(episodes.data()), episodes.size());
  std::filesystem::rename(jsonl, root / "meta" / "episodes.jsonl");
  try {
    const kccd::logs::LerobotDataset d = kccd::logs::openLerobotDataset(root.string());
    if (!(d.fps > 0 && std::isfinite(d.fps))) std::abort();
    for (std::size_t i = 1; i < d.episodes.size(); ++i)
      if (d.episodes[i].index <= d.episodes[i - 1].index) std::abort();
    for (const kccd::logs::LerobotEpisode& e : d.episodes) {
      if (d.episode(e.index).index != e.index) std::abort();
      try {
        (void)d.dataFile(e);
        for (const std::string& key : d.cameras()) (void)d.video(e, key);
      } catch (const kccd::InputError& err) {
        kccd::fuzz::checkMessage(err.what(), root.string());
      }
    }
  } catch (const kccd::InputError& e) {
    kccd::fuzz::checkMessage(e.what(), root.string());
  }
  return 0;
}
