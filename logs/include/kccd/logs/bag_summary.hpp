// What a robot log holds, per topic: type, message count, first and last log time, rate, and how
// far each message's header stamp lies behind its log time (`kccd bag info`); per topic also its
// publishers (a ROS 1 bag's connections, an MCAP file's channels), one row each.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace kccd::logs {

/// One topic of a log, or one publisher of a topic (see `publishers`). A topic's text fields are
/// its publishers', with ", " between values that differ (a topic two nodes publish in two types).
struct TopicSummary {
  std::string topic;
  std::string type;              ///< the schema's name, e.g. "sensor_msgs/msg/JointState" ("" without a schema)
  std::string schema_encoding;   ///< e.g. "ros2msg" ("" without a schema)
  std::string message_encoding;  ///< e.g. "cdr"
  std::uint64_t count = 0;
  std::uint64_t first_log_time = 0, last_log_time = 0;  ///< nanoseconds
  /// Messages with a std_msgs/Header stamp (decoded from the log's own definitions), and of those
  /// the stamps that are zero (unset by the publisher: not counted in the skew).
  std::uint64_t stamped = 0, zero_stamps = 0;
  /// Log time minus header stamp over the stamped messages, seconds: least, median, most.
  double skew_min = 0.0, skew_median = 0.0, skew_max = 0.0;
  /// Why the stamps were not read (no schema, an encoding this reader does not decode, no header).
  std::string no_stamps;
  /// Where the definition came from: "stored" (in the log), "built in" (the log stores none), "none".
  std::string definition = "none";
  /// A publisher's channel metadata (a ROS 1 connection's callerid, md5sum, latching); empty in a
  /// topic's row.
  std::vector<std::pair<std::string, std::string>> metadata;
  /// The topic's publishers: each channel on it (a ROS 1 connection, an MCAP channel) as a row of
  /// its own messages, in the order the log defines them (one for a topic of one channel). A
  /// recorder opens a connection per publishing node, so a busy topic such as /tf has many; the
  /// topic's row sums them. Empty in a publisher's row.
  std::vector<TopicSummary> publishers;
  /// Messages per second between the first and the last (0 for fewer than two).
  double rate() const;
};

/// A whole log.
struct BagSummary {
  std::string path, format;  ///< format: "MCAP" or "rosbag2 sqlite3"
  std::string profile, library;
  std::uint64_t messages = 0, first_log_time = 0, last_log_time = 0;
  std::vector<TopicSummary> topics;   ///< by topic name
  std::map<std::string, int> chunks;  ///< chunks by compression
  std::string damage;                 ///< empty, or where the file was cut short (the messages before it are counted)
};

/// Reads every message of the log at `path` (see openLog) once. Throws InputError for a file that is not
/// a log this reader knows, a damaged record, a definition that does not parse or a message that
/// does not decode as its definition says (naming the file, topic, type and byte offset).
BagSummary summarizeBag(const std::string& path);

}  // namespace kccd::logs
