#include "kccd/logs/log_reader.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <yaml-cpp/yaml.h>

#include "kccd/file_reader.hpp"
#include "kccd/yaml_reader.hpp"

#include "kccd/input_error.hpp"
#include "kccd/logs/db3_reader.hpp"
#include "kccd/logs/mcap_reader.hpp"
#include "kccd/logs/ros1_reader.hpp"

namespace kccd::logs {

namespace {

// A rosbag2 folder: its metadata.yaml lists the storage and the files in order.
std::vector<std::string> folderFiles(const std::string& dir) {
  const std::filesystem::path meta = std::filesystem::path(dir) / "metadata.yaml";
  std::error_code ec;
  if (!std::filesystem::exists(meta, ec))
    throw InputError(InputLocation{dir, 0, 0, "folder"}, "not a rosbag2 folder (no metadata.yaml)");
  // A bounded regular file (a FIFO or /dev/zero in its place is refused without reading), then
  // one checked YAML document (bounded nesting and aliases) before yaml-cpp builds nodes.
  const YamlReader reader(meta.string());
  const YAML::Node root = reader.load(readRegularFile(meta.string(), 16u << 20, "rosbag2 metadata file"));
  const YAML::Node info = root["rosbag2_bagfile_information"];
  if (!info || !info.IsMap())
    throw InputError(InputLocation{meta.string(), 0, 0, "rosbag2_bagfile_information"}, "missing");
  std::string storage;
  try {
    storage = info["storage_identifier"] ? info["storage_identifier"].as<std::string>() : "";
  } catch (const YAML::Exception&) {
  }
  std::vector<std::string> files;
  const YAML::Node paths = info["relative_file_paths"];
  if (paths && paths.IsSequence())
    for (const YAML::Node& p : paths) {
      if (!p.IsScalar())
        throw InputError(
            InputLocation{meta.string(), static_cast<std::size_t>(p.Mark().line + 1), 0, "relative_file_paths"},
            "expected file names");
      const std::string name = p.as<std::string>();
      if (name.empty() || name.find("..") != std::string::npos || name.front() == '/')
        throw InputError(
            InputLocation{meta.string(), static_cast<std::size_t>(p.Mark().line + 1), 0, "relative_file_paths"},
            "'" + printable(name, 60) + "' is not a file in the folder");
      files.push_back((std::filesystem::path(dir) / name).string());
    }
  if (files.empty()) throw InputError(InputLocation{meta.string(), 0, 0, "relative_file_paths"}, "lists no file");
  if (!storage.empty() && storage != "sqlite3" && storage != "mcap")
    throw InputError(InputLocation{meta.string(), 0, 0, "storage_identifier"},
                     "'" + printable(storage, 40) + "' is not sqlite3 or mcap");
  return files;
}

}  // namespace

std::unique_ptr<LogReader> openLog(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    const std::vector<std::string> files = folderFiles(path);
    const auto is_mcap = [](const std::string& f) { return f.size() >= 5 && f.compare(f.size() - 5, 5, ".mcap") == 0; };
    const auto mcaps = std::count_if(files.begin(), files.end(), is_mcap);
    if (mcaps == 1 && files.size() == 1) return std::make_unique<McapReader>(files.front());
    if (mcaps == static_cast<std::ptrdiff_t>(files.size())) return std::make_unique<SplitMcapReader>(files, path);
    if (mcaps > 0)
      throw InputError(InputLocation{path, 0, 0, "folder"},
                       "its metadata.yaml lists MCAP files and files of another kind (a bag has one storage)");
    return std::make_unique<Db3Reader>(files, path);
  }
  // Only a regular file is opened: a FIFO would block the open itself.
  if (const auto st = std::filesystem::status(path, ec);
      std::filesystem::exists(st) && !std::filesystem::is_regular_file(st))
    throw InputError(InputLocation{path, 0, 0, "file"}, "not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int error = errno;
    throw InputError(InputLocation{path, 0, 0, "file"},
                     std::string("cannot be opened (") +
                         (std::filesystem::exists(path, ec) ? std::strerror(error) : "no such file") + ")");
  }
  char magic[16] = {};
  in.read(magic, 16);
  const std::streamsize got = in.gcount();
  if (got == 16 && std::memcmp(magic, "SQLite format 3", 16) == 0)
    return std::make_unique<Db3Reader>(std::vector<std::string>{path});
  if (got >= 9 && std::memcmp(magic, "#ROSBAG V", 9) == 0)
    return std::make_unique<Ros1Reader>(path);  // which checks the version
  if (got >= 8 && std::memcmp(magic, "\x89MCAP", 5) == 0)
    return std::make_unique<McapReader>(path);  // which checks the rest
  throw InputError(InputLocation{path, 0, 0, "byte 0"},
                   got == 0 ? std::string("an empty file, not a robot log")
                            : "not a robot log kccd reads: its first bytes are those of no MCAP file, rosbag2 sqlite3 "
                              "(.db3) file or ROS 1 bag "
                              "(a rosbag2 folder is given as the folder)");
}

}  // namespace kccd::logs
