#include "kccd/logs/mcap_writer.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

#include "mcap_format.hpp"

namespace kccd::logs {
namespace {

using namespace detail::mcap;  // the magic, the opcodes, the CRC

// One record's bytes: the opcode, the content's length (filled in by done()) and the content, its
// fields little-endian as the spec lays them out.
class RecordBytes {
 public:
  explicit RecordBytes(std::uint8_t opcode) : b_(9, 0) { b_[0] = opcode; }
  template <class T>
  RecordBytes& num(T v) {
    for (std::size_t i = 0; i < sizeof(T); ++i) b_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    return *this;
  }
  RecordBytes& str(std::string_view s) {  // a uint32 length, then the bytes
    if (s.size() > std::numeric_limits<std::uint32_t>::max())
      throw std::invalid_argument("McapWriter: a string of 4 GiB or more");
    num(static_cast<std::uint32_t>(s.size()));
    b_.insert(b_.end(), s.begin(), s.end());
    return *this;
  }
  // Overwrites the uint32 at content offset `at` (a map's byte length, known after its entries).
  void patch32(std::size_t at, std::uint32_t v) {
    for (std::size_t i = 0; i < 4; ++i) b_[9 + at + i] = static_cast<std::uint8_t>(v >> (8 * i));
  }
  std::size_t contentSize() const { return b_.size() - 9; }
  // The record, its length field set to the content's size plus `more` bytes written after it.
  std::vector<std::uint8_t> done(std::uint64_t more = 0) {
    const std::uint64_t n = b_.size() - 9 + more;
    for (std::size_t i = 0; i < 8; ++i) b_[1 + i] = static_cast<std::uint8_t>(n >> (8 * i));
    return std::move(b_);
  }

 private:
  std::vector<std::uint8_t> b_;
};

}  // namespace

McapWriter::McapWriter(std::ostream& out, std::string_view profile, std::string_view library) : out_(out) {
  emit(kMagic);
  emit(RecordBytes(kHeader).str(profile).str(library).done());
}

void McapWriter::emit(std::span<const std::uint8_t> bytes) {
  out_.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  crc_ = crc32Of(crc_, bytes.data(), bytes.size());
  pos_ += bytes.size();
}

std::uint16_t McapWriter::addSchema(std::string_view name, std::string_view encoding, std::string_view data) {
  if (finished_) throw std::invalid_argument("McapWriter: a schema added after finish()");
  if (schemas_.size() >= 0xFFFF) throw std::invalid_argument("McapWriter: more than 65535 schemas");
  const auto id = static_cast<std::uint16_t>(schemas_.size() + 1);
  RecordBytes r(kSchema);
  r.num(id).str(name).str(encoding).str(data);
  schemas_.push_back(r.done());
  emit(schemas_.back());
  return id;
}

std::uint16_t McapWriter::addChannel(std::uint16_t schema_id, std::string_view topic, std::string_view message_encoding,
                                     const std::vector<std::pair<std::string, std::string>>& metadata) {
  if (finished_) throw std::invalid_argument("McapWriter: a channel added after finish()");
  if (schema_id > schemas_.size())
    throw std::invalid_argument("McapWriter: channel " + std::string(topic) + ": no schema " +
                                std::to_string(schema_id));
  if (channels_.size() > 0xFFFF) throw std::invalid_argument("McapWriter: more than 65536 channels");
  const auto id = static_cast<std::uint16_t>(channels_.size());
  RecordBytes r(kChannel);
  r.num(id).num(schema_id).str(topic).str(message_encoding);
  const std::size_t map_at = r.contentSize();
  r.num(std::uint32_t{0});  // the map's byte length, patched below
  for (const auto& [key, value] : metadata) r.str(key).str(value);
  r.patch32(map_at, static_cast<std::uint32_t>(r.contentSize() - map_at - 4));
  channels_.push_back(r.done());
  emit(channels_.back());
  counts_[id] = 0;
  return id;
}

void McapWriter::write(std::uint16_t channel_id, std::uint64_t log_time, std::uint64_t publish_time,
                       std::span<const std::uint8_t> data) {
  if (finished_) throw std::invalid_argument("McapWriter: a message written after finish()");
  if (!counts_.count(channel_id))
    throw std::invalid_argument("McapWriter: a message on channel " + std::to_string(channel_id) +
                                ", which was never added");
  RecordBytes r(kMessage);
  r.num(channel_id).num(sequences_[channel_id]++).num(log_time).num(publish_time);
  emit(r.done(data.size()));
  emit(data);
  first_time_ = messages_ == 0 ? log_time : std::min(first_time_, log_time);
  last_time_ = std::max(last_time_, log_time);
  ++messages_;
  ++counts_[channel_id];
}

void McapWriter::finish() {
  if (finished_) throw std::invalid_argument("McapWriter: finish() called twice");
  finished_ = true;
  // Data End: the CRC of everything before it (the magic included).
  emit(RecordBytes(kDataEnd).num(crc_).done());
  const std::uint64_t summary_start = pos_;
  crc_ = 0;
  // The summary: each group of records, where it starts and how long it is.
  struct Group {
    std::uint8_t opcode;
    std::uint64_t start, length;
  };
  std::vector<Group> groups;
  const auto group = [&](std::uint8_t opcode, const std::vector<std::vector<std::uint8_t>>& records) {
    if (records.empty()) return;
    const std::uint64_t start = pos_;
    for (const std::vector<std::uint8_t>& r : records) emit(r);
    groups.push_back({opcode, start, pos_ - start});
  };
  group(kSchema, schemas_);
  group(kChannel, channels_);
  RecordBytes stats(kStatistics);
  stats.num(messages_)
      .num(static_cast<std::uint16_t>(schemas_.size()))
      .num(static_cast<std::uint32_t>(channels_.size()))
      .num(std::uint32_t{0})  // attachments
      .num(std::uint32_t{0})  // metadata
      .num(std::uint32_t{0})  // chunks
      .num(first_time_)
      .num(last_time_)
      .num(static_cast<std::uint32_t>(counts_.size() * 10));  // channel_message_counts: uint16 -> uint64
  for (const auto& [channel, count] : counts_) stats.num(channel).num(count);
  group(kStatistics, {stats.done()});
  const std::uint64_t offsets_start = pos_;
  for (const Group& g : groups) emit(RecordBytes(kSummaryOffset).num(g.opcode).num(g.start).num(g.length).done());
  // Footer: its summary CRC covers the summary section and the footer up to that field.
  RecordBytes footer(kFooter);
  footer.num(summary_start).num(offsets_start);
  std::vector<std::uint8_t> bytes = footer.done(4);
  const std::uint32_t summary_crc = crc32Of(crc_, bytes.data(), bytes.size());
  for (std::size_t i = 0; i < 4; ++i) bytes.push_back(static_cast<std::uint8_t>(summary_crc >> (8 * i)));
  emit(bytes);
  emit(kMagic);
}

}  // namespace kccd::logs
