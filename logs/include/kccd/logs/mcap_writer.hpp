// Writing MCAP files (https://mcap.dev/spec, version 0): the magic and the Header, schemas and
// channels as they are added, messages in one unchunked data section, then the Data End record, a
// summary section (schemas, channels, statistics, summary offsets) and the Footer, with the CRC-32s
// of the data and summary sections filled in. What McapReader and other projects' readers read.
#pragma once

#include <cstdint>
#include <map>
#include <ostream>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace kccd::logs {

/// Streams one MCAP file into `out` (a binary stream). A file that finish() did not close has no
/// Footer, so every reader sees it as cut short. The stream's state says whether the bytes were
/// written; the writer does not check it. Every call after finish(), and a string (name, topic,
/// definition, metadata) of 4 GiB or more, throws std::invalid_argument.
class McapWriter {
 public:
  /// Writes the leading magic and the Header record: `profile` (e.g. "ros2") and `library` (the writer).
  McapWriter(std::ostream& out, std::string_view profile, std::string_view library);
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  /// Writes a Schema record (`encoding` e.g. "ros2msg", `data` the definition) and returns its id
  /// (1, 2, ... 65535; std::invalid_argument beyond).
  std::uint16_t addSchema(std::string_view name, std::string_view encoding, std::string_view data);

  /// Writes a Channel record for schema `schema_id` (0: none) and returns its id (0, 1, ... 65535).
  /// Throws std::invalid_argument for a schema id never returned by addSchema, or beyond 65536 channels.
  std::uint16_t addChannel(std::uint16_t schema_id, std::string_view topic, std::string_view message_encoding,
                           const std::vector<std::pair<std::string, std::string>>& metadata = {});

  /// Writes a Message record on `channel_id`, numbered by its channel from 0 (the sequence);
  /// times in nanoseconds. Throws std::invalid_argument for a channel never added.
  void write(std::uint16_t channel_id, std::uint64_t log_time, std::uint64_t publish_time,
             std::span<const std::uint8_t> data);

  /// Ends the file: Data End (with the data section's CRC), the summary section, the Footer (with
  /// the summary's CRC) and the closing magic.
  void finish();

 private:
  void emit(std::span<const std::uint8_t> bytes);

  std::ostream& out_;
  std::uint64_t pos_ = 0;                           // bytes written
  std::uint32_t crc_ = 0;                           // CRC-32 of the section being written
  std::vector<std::vector<std::uint8_t>> schemas_;  // the records as written, for the summary
  std::vector<std::vector<std::uint8_t>> channels_;
  std::map<std::uint16_t, std::uint32_t> sequences_;  // per channel: the next sequence number
  std::map<std::uint16_t, std::uint64_t> counts_;     // per channel: messages written
  std::uint64_t messages_ = 0, first_time_ = 0, last_time_ = 0;
  bool finished_ = false;
};

}  // namespace kccd::logs
