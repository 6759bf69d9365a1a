// Reading MCAP files (https://mcap.dev/spec, version 0) as a stream of messages in log-time order:
// the records in file order, chunks decompressed one at a time (none, zstd, lz4 frames), CRCs
// checked where the writer recorded them. A linear scan needs no index, so a recording that crashed
// before writing its summary reads the same as a finished one. Where the summary's chunk index
// shows chunks whose time ranges overlap (messages written out of time order), the chunks are read
// by start time instead and their messages merged by log time. SplitMcapReader reads a rosbag2
// folder of several MCAP files as one log.
#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "kccd/logs/log_reader.hpp"

namespace kccd::logs {

/// Streams one MCAP file's messages. Memory is bounded by the largest record or decompressed
/// chunk (by the chunks open at once where chunks overlap in time), not by the file. Every length field is checked
/// against the bytes that remain before anything is allocated for it.
class McapReader final : public LogReader {
 public:
  /// Opens `path` and checks the leading magic; throws InputError naming the file otherwise.
  explicit McapReader(const std::string& path);
  ~McapReader() override;
  McapReader(const McapReader&) = delete;
  McapReader& operator=(const McapReader&) = delete;

  /// The next message in log-time order (file order for equal times, and for a file whose chunks
  /// do not overlap in time or that has no chunk index); false after the last one. Throws InputError ("FILE: byte N:
  /// problem") for a CRC mismatch, an unknown compression, a record that contradicts itself or a
  /// message on a channel never defined. A file cut short ends the stream early: see damage().
  bool next(LogMessage& out) override;

  /// Empty, or why the stream ended before the file's proper end (e.g. "cut short at byte 1234
  /// inside a Chunk record") — the messages before it were read.
  const std::string& damage() const override { return damage_; }
  std::string format() const override { return "MCAP"; }
  /// The header's profile (e.g. "ros2", "ros1") and library.
  std::string profile() const override { return profile_; }
  std::string library() const override { return library_; }
  /// The schemas and channels seen so far, by id.
  const std::map<std::uint16_t, Schema>& schemas() const { return schemas_; }
  const std::map<std::uint16_t, Channel>& channels() const { return channels_; }
  /// The file's name as messages show it.
  const std::string& path() const { return path_; }
  std::uint64_t fileSize() const { return size_; }
  /// Chunks read so far, and their compressions (e.g. {"zstd": 12}).
  std::map<std::string, int> chunks() const override { return chunks_; }
  /// True when the chunks overlap in time and are merged by log time (see above).
  bool merging() const { return merge_ != nullptr; }

 private:
  bool readRecord(std::uint8_t& opcode, std::vector<std::uint8_t>& content, std::uint64_t& at);
  void handle(std::uint8_t opcode, std::span<const std::uint8_t> content, std::uint64_t at, bool in_chunk);
  void openChunk(std::span<const std::uint8_t> content, std::uint64_t at);
  // The record at `pos` of a chunk's records (advancing `pos`): its opcode and content; fails
  // naming the chunk at `at` for one that runs past the end or does not belong in a chunk.
  std::span<const std::uint8_t> chunkRecord(const std::vector<std::uint8_t>& records, std::size_t& pos,
                                            std::uint64_t at, std::uint8_t& op) const;
  void decompressChunk(std::span<const std::uint8_t> content, std::uint64_t at, std::vector<std::uint8_t>& out);
  struct Merge;
  bool readIndex();
  bool nextMerged(LogMessage& out);
  [[noreturn]] void fail(std::uint64_t at, const std::string& problem) const;
  void cut(std::uint64_t at, const std::string& where);

  std::string path_;
  std::ifstream in_;
  std::uint64_t size_ = 0, pos_ = 0;
  std::uint64_t decompress_left_ = 0;  // what chunks may still decompress to (a bound on bombs)
  std::uint32_t data_crc_ = 0;         // CRC-32 of every byte read before the Data End record
  bool data_crc_on_ = true;
  std::uint32_t summary_crc_ = 0;  // CRC-32 from the summary section's start
  bool in_summary_ = false, ended_ = false;
  std::string damage_, profile_, library_;
  std::map<std::uint16_t, Schema> schemas_;
  std::map<std::uint16_t, Channel> channels_;
  std::map<std::string, int> chunks_;
  std::vector<std::uint8_t> record_;  // the current record's content
  std::vector<std::uint8_t> chunk_;   // the current chunk's records, decompressed
  std::uint64_t chunk_at_ = 0, chunk_pos_ = 0;
  bool pending_ = false;  // handle() found a message for next() to return
  LogMessage message_;
  std::unique_ptr<Merge> merge_;  // chunks read by start time (overlapping chunks), else null
};

/// Streams a rosbag2 bag split into several MCAP files (the relative_file_paths of its
/// metadata.yaml) as one log, as Db3Reader reads a split .db3 bag: the files in that order, one
/// open at a time, each in its own log-time order (a recorder splits its log by size or time, so
/// that order is the log's). A channel is one channel across the files (the same topic, encoding,
/// metadata and schema), whatever id each file gives it. A file cut short ends its own part, its
/// damage named with the file's name, and the next file is read.
class SplitMcapReader final : public LogReader {
 public:
  /// Opens the first file after checking that every file is there; `label` names the log (the
  /// folder). Throws InputError naming the file.
  SplitMcapReader(std::vector<std::string> files, std::string label);
  ~SplitMcapReader() override;

  bool next(LogMessage& out) override;
  const std::string& damage() const override { return damage_; }
  std::string format() const override { return "MCAP"; }
  /// The first file's.
  std::string profile() const override;
  std::string library() const override;
  std::map<std::string, int> chunks() const override;
  /// "NAME byte N": the file's name and the byte in it.
  std::string place(std::uint64_t offset) const override;

 private:
  void open(std::size_t file);
  const Channel& channelOf(const LogMessage& m);
  std::vector<std::string> files_;
  std::string label_, damage_, profile_, library_;
  std::size_t file_ = 0;
  bool done_ = false;
  std::unique_ptr<McapReader> reader_;
  std::map<std::string, int> chunks_;                     // of the files read to their end
  std::map<std::string, std::uint16_t> channel_of_key_;   // across files: a channel's identity -> its id
  std::map<std::uint16_t, std::uint16_t> file_channels_;  // this file's channel ids -> ours
  std::map<std::uint16_t, Channel> channels_;
  std::map<std::uint16_t, Schema> schemas_;  // by the id of the channel that uses it
};

}  // namespace kccd::logs
