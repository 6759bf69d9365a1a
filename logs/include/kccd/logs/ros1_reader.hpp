// Reading ROS 1 bags (format 2.0): records in file order, chunks stored plain, bz2 or lz4, the
// connections' message definitions as each channel's schema ("ros1msg"). The index at the end is
// not needed: a bag whose recording was killed before writing it reads like a finished one.
#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "kccd/logs/log_reader.hpp"

namespace kccd::logs {

/// Streams one ROS 1 bag's messages (see LogReader). LogMessage::offset is the record's file
/// offset (its chunk's when chunked); log_time is the record's time.
class Ros1Reader final : public LogReader {
 public:
  /// Opens `path` and checks "#ROSBAG V2.0"; throws InputError naming the file otherwise.
  explicit Ros1Reader(const std::string& path);
  ~Ros1Reader() override;

  bool next(LogMessage& out) override;
  const std::string& damage() const override { return damage_; }
  std::string format() const override { return "ROS 1 bag"; }
  std::string profile() const override { return "ros1"; }
  std::map<std::string, int> chunks() const override { return chunks_; }

 private:
  bool record(std::span<const std::uint8_t> header, std::span<const std::uint8_t> data, std::uint64_t at,
              bool in_chunk);
  [[noreturn]] void fail(std::uint64_t at, const std::string& problem) const;
  // The bytes of a chunk record at `at` that the file cuts short (its header read, `declared`
  // bytes of data of which fewer remain) as the open chunk: plain, or what of it decompresses.
  // Returns what the damage adds (": an uncompressed chunk, ..."), "" for a record that is no
  // chunk this reader takes.
  std::string openCutChunk(std::uint64_t at, std::uint32_t declared);

  std::string path_, damage_;
  std::ifstream in_;
  std::uint64_t size_ = 0, pos_ = 0;
  std::uint64_t decompress_left_ = 0;  // what chunks may still decompress to (a bound on bombs)
  std::vector<std::uint8_t> header_, data_, chunk_;
  std::size_t chunk_pos_ = 0;
  std::uint64_t chunk_at_ = 0;
  bool chunk_cut_ = false;  // the open chunk was cut short: its last record may be part of one
  bool ended_ = false, have_header_ = false;
  std::uint64_t index_pos_ = 0;  // the bag header's: where the index section starts (0: not closed)
  std::uint32_t chunk_count_ = 0, chunk_infos_ = 0;
  std::map<std::uint32_t, std::uint16_t> channel_of_conn_;
  std::map<std::uint16_t, Channel> channels_;
  std::map<std::uint16_t, Schema> schemas_;
  std::map<std::string, int> chunks_;
  LogMessage message_;
};

}  // namespace kccd::logs
