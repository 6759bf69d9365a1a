// One interface over every robot log format this part reads: a stream of messages with their
// channels and schemas, and the damage that ended it early. openLog picks the reader by content.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include "kccd/logs/log_message.hpp"

namespace kccd::logs {

/// A robot log read as a stream of messages (see McapReader for the views' lifetime).
class LogReader {
 public:
  virtual ~LogReader() = default;
  /// The next message; false after the last. Throws InputError for damage that is not a cut.
  virtual bool next(LogMessage& out) = 0;
  /// Empty, or why the stream ended before the log's proper end.
  virtual const std::string& damage() const = 0;
  /// "MCAP", "rosbag2 sqlite3" or "ROS 1 bag".
  virtual std::string format() const = 0;
  /// The writer's profile and library (empty when the format has none).
  virtual std::string profile() const { return {}; }
  virtual std::string library() const { return {}; }
  /// Chunks read so far by compression (formats with chunks).
  virtual std::map<std::string, int> chunks() const { return {}; }
  /// Where a message's LogMessage::offset points, as messages name it: "byte N" (a file offset)
  /// or "row N" (a table row).
  virtual std::string place(std::uint64_t offset) const { return "byte " + std::to_string(offset); }
};

/// Opens a log by what it holds: an MCAP file, a rosbag2 sqlite3 file (.db3), a ROS 1 bag, or a
/// rosbag2 folder (metadata.yaml and its .db3 or .mcap files, read as one log in the order it lists
/// them). Throws InputError naming the path.
std::unique_ptr<LogReader> openLog(const std::string& path);

}  // namespace kccd::logs
