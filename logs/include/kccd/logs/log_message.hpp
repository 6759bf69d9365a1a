// A robot log's messages as every reader hands them on: the message with its channel (topic,
// encoding) and schema (the type's name and definition).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace kccd::logs {

/// A schema record: how a channel's messages are described (e.g. name "sensor_msgs/msg/JointState",
/// encoding "ros2msg", data the definition text).
struct Schema {
  std::uint16_t id = 0;
  std::string name, encoding, data;
};

/// A channel record: a topic, its message encoding (e.g. "cdr", "ros1") and its schema (0: none).
struct Channel {
  std::uint16_t id = 0, schema_id = 0;
  std::string topic, message_encoding;
  std::vector<std::pair<std::string, std::string>> metadata;
};

/// One message. The views (channel, schema, data) stay valid until the next call to next().
struct LogMessage {
  const Channel* channel = nullptr;
  const Schema* schema = nullptr;  ///< null when the channel has no schema (schema id 0)
  std::uint32_t sequence = 0;
  std::uint64_t log_time = 0, publish_time = 0;  ///< nanoseconds
  std::span<const std::uint8_t> data;
  std::uint64_t offset = 0;  ///< where it is: see LogReader::place (MCAP: the record's or its chunk's file offset)
};

}  // namespace kccd::logs
