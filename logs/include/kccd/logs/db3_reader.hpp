// Reading rosbag2's sqlite3 storage (.db3): the topics table and the messages in timestamp order.
// The message definitions come from the message_definitions table where the recorder stored them
// (Jazzy and later); older bags store none, and the definitions of the messages this suite reads
// (sensor_msgs JointState, Image, CompressedImage, CameraInfo) are built in.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "kccd/logs/log_reader.hpp"

namespace kccd::logs {

/// The ROS 2 definition text (with dependencies) built in for `type` ("pkg/msg/Type"), or empty.
std::string builtinDefinition(const std::string& type);

/// Streams the messages of one or more .db3 files (a split bag's files in order). A channel whose
/// definition is the built-in one carries the metadata ("kccd_definition", "built in").
class Db3Reader final : public LogReader {
 public:
  /// Opens the files; `label` names the log in messages (default: the first file). Throws InputError.
  explicit Db3Reader(std::vector<std::string> files, std::string label = "");
  ~Db3Reader() override;

  bool next(LogMessage& out) override;
  const std::string& damage() const override { return damage_; }
  std::string format() const override { return "rosbag2 sqlite3"; }
  std::string place(std::uint64_t offset) const override;

 private:
  struct Db;
  void open(std::size_t file);
  std::string filePrefix() const;  // the file's name and ": " in a split bag, else ""
  std::vector<std::string> files_;
  std::string label_, damage_;
  std::size_t file_ = 0;
  std::unique_ptr<Db> db_;
  std::map<std::string, std::uint16_t> channel_of_topic_;  // across files: one channel per topic
  std::map<std::int64_t, std::uint16_t> topic_ids_;        // this file's topic ids
  std::map<std::uint16_t, Channel> channels_;
  std::map<std::uint16_t, Schema> schemas_;
  std::vector<std::uint8_t> data_;
  std::uint64_t row_ = 0;
};

}  // namespace kccd::logs
