#include "kccd/logs/mcap_reader.hpp"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <limits>

#include "decompress.hpp"
#include "kccd/input_error.hpp"
#include "mcap_format.hpp"

namespace kccd::logs {
namespace {

using namespace detail::mcap;  // the magic, the opcodes, the CRC
// A decompressed chunk may be larger than the file, but not without limit.
constexpr std::uint64_t kMaxChunk = std::uint64_t{1} << 31;

const char* opName(std::uint8_t op) {
  static const char* names[] = {
      "?",        "Header",         "Footer",         "Schema",     "Channel",          "Message",
      "Chunk",    "Message Index",  "Chunk Index",    "Attachment", "Attachment Index", "Statistics",
      "Metadata", "Metadata Index", "Summary Offset", "Data End"};
  return op < 16 ? names[op] : "unknown";
}

// Little-endian fields of one record, each checked against the record's end.
class Fields {
 public:
  Fields(std::span<const std::uint8_t> b, const char* record) : b_(b), record_(record) {}
  template <class T>
  T num(const char* what) {
    need(sizeof(T), what);
    T v = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i) v |= static_cast<T>(static_cast<T>(b_[pos_ + i]) << (8 * i));
    pos_ += sizeof(T);
    return v;
  }
  std::string str(const char* what) {
    const std::uint32_t n = num<std::uint32_t>(what);
    need(n, what);
    std::string s(reinterpret_cast<const char*>(b_.data() + pos_), n);
    pos_ += n;
    return s;
  }
  std::span<const std::uint8_t> bytes32(const char* what) { return take(num<std::uint32_t>(what), what); }
  std::span<const std::uint8_t> bytes64(const char* what) { return take(num<std::uint64_t>(what), what); }
  std::span<const std::uint8_t> rest() { return take(b_.size() - pos_, "data"); }
  std::span<const std::uint8_t> take(std::uint64_t n, const char* what) {
    need(n, what);
    const auto s = b_.subspan(pos_, static_cast<std::size_t>(n));
    pos_ += static_cast<std::size_t>(n);
    return s;
  }
  std::size_t position() const { return pos_; }

 private:
  void need(std::uint64_t n, const char* what) {
    if (n > b_.size() - pos_)
      throw std::out_of_range(std::string("the ") + record_ + " record is too short for its " + what + " (" +
                              std::to_string(n) + " bytes at " + std::to_string(pos_) + " of " +
                              std::to_string(b_.size()) + ")");
  }
  std::span<const std::uint8_t> b_;
  std::size_t pos_ = 0;
  const char* record_;
};

// The little-endian 64-bit number at `p` (record lengths, times).
std::uint64_t le64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return v;
}

}  // namespace

McapReader::McapReader(const std::string& path) : path_(path) {
  in_.open(path, std::ios::binary);
  if (!in_) throw InputError(InputLocation{path, 0, 0, "file"}, "cannot be opened");
  in_.seekg(0, std::ios::end);
  const std::streamoff end = in_.tellg();
  in_.seekg(0);
  if (end < 0) throw InputError(InputLocation{path, 0, 0, "file"}, "cannot be read");
  size_ = static_cast<std::uint64_t>(end);
  decompress_left_ = detail::decompressBudget(size_);
  std::uint8_t magic[8] = {};
  if (size_ < 8 || !in_.read(reinterpret_cast<char*>(magic), 8) || std::memcmp(magic, kMagic, 8) != 0)
    throw InputError(InputLocation{path, 0, 0, "byte 0"},
                     "not an MCAP file (its first 8 bytes are not the MCAP magic)");
  data_crc_ = crc32Of(0, magic, 8);
  pos_ = 8;
  if (!readIndex()) {
    merge_.reset();
    schemas_.clear();
    channels_.clear();
    in_.clear();
    in_.seekg(8);
  }
}

McapReader::~McapReader() = default;

// Merging chunks that overlap in time: the chunk index in start-time order, the chunks open now
// (decompressed, their messages sorted by log time) and where each stands.
struct McapReader::Merge {
  struct Chunk {
    std::uint64_t start = 0, end = 0, offset = 0, length = 0;
  };
  struct Entry {
    std::uint64_t log_time = 0;
    std::size_t record = 0;  // offset of the message's content in the chunk's records
    std::size_t size = 0;
  };
  struct Open {
    std::uint64_t at = 0;  // the chunk's file offset
    std::vector<std::uint8_t> records;
    std::vector<Entry> messages;
    std::size_t next = 0;
  };
  std::vector<Chunk> order;  // by start time, then file offset
  std::size_t opened = 0;
  std::vector<std::unique_ptr<Open>> open;
  std::unique_ptr<Open> last;  // the chunk of the message returned last (its bytes are the caller's until next())
};

bool McapReader::readIndex() {
  // Footer: opcode, length 20, summary_start, summary_offset_start, summary_crc; then the magic.
  constexpr std::uint64_t kFooterBytes = 9 + 20;
  if (size_ < 8 + kFooterBytes + 8) return false;
  std::vector<std::uint8_t> tail(kFooterBytes + 8);
  in_.seekg(static_cast<std::streamoff>(size_ - tail.size()));
  if (!in_.read(reinterpret_cast<char*>(tail.data()), static_cast<std::streamsize>(tail.size()))) return false;
  if (tail[0] != kFooter || std::memcmp(tail.data() + kFooterBytes, kMagic, 8) != 0) return false;
  const std::uint64_t summary_start = le64(tail.data() + 9);
  const std::uint64_t summary_end = size_ - tail.size();
  if (summary_start < 8 || summary_start >= summary_end) return false;
  std::vector<std::uint8_t> summary(static_cast<std::size_t>(summary_end - summary_start));
  in_.seekg(static_cast<std::streamoff>(summary_start));
  if (!in_.read(reinterpret_cast<char*>(summary.data()), static_cast<std::streamsize>(summary.size()))) return false;
  // A summary whose CRC does not match is left to the linear scan, which names the damage.
  std::uint32_t crc = 0;
  for (int i = 0; i < 4; ++i) crc |= static_cast<std::uint32_t>(tail[9 + 16 + i]) << (8 * i);
  if (crc != 0 && crc32Of(crc32Of(0, summary.data(), summary.size()), tail.data(), 9 + 16) != crc) return false;
  auto merge = std::make_unique<Merge>();
  try {
    for (std::size_t p = 0; p < summary.size();) {
      if (summary.size() - p < 9) return false;
      const std::uint8_t op = summary[p];
      const std::uint64_t len = le64(summary.data() + p + 1);
      if (len > summary.size() - p - 9) return false;
      const std::span<const std::uint8_t> content(summary.data() + p + 9, static_cast<std::size_t>(len));
      const std::uint64_t at = summary_start + p;
      p += 9 + static_cast<std::size_t>(len);
      if (op == kSchema || op == kChannel) {
        handle(op, content, at, false);
      } else if (op == kChunkIndex) {
        Fields f(content, "Chunk Index");
        Merge::Chunk c;
        c.start = f.num<std::uint64_t>("message_start_time");
        c.end = f.num<std::uint64_t>("message_end_time");
        c.offset = f.num<std::uint64_t>("chunk_start_offset");
        c.length = f.num<std::uint64_t>("chunk_length");
        if (c.offset < 8 || c.length < 9 || c.offset > summary_start || c.length > summary_start - c.offset ||
            c.start > c.end)
          return false;
        merge->order.push_back(c);
      }
    }
  } catch (const std::exception&) {
    return false;  // the linear scan says what is wrong, where
  }
  if (merge->order.size() < 2) return false;
  // Overlap: a chunk (in file order) that starts before an earlier one ends.
  std::sort(merge->order.begin(), merge->order.end(),
            [](const Merge::Chunk& a, const Merge::Chunk& b) { return a.offset < b.offset; });
  bool overlap = false;
  std::uint64_t latest = 0;
  for (const Merge::Chunk& c : merge->order) {
    overlap = overlap || c.start < latest;
    latest = std::max(latest, c.end);
  }
  if (!overlap) return false;
  // The data section's records between chunks: schemas and channels are taken, and a message outside
  // every chunk (which the index does not place) leaves the file to the linear scan.
  std::vector<std::uint8_t> content;
  for (std::uint64_t p = 8; p < summary_start;) {
    std::uint8_t head[9];
    in_.seekg(static_cast<std::streamoff>(p));
    if (summary_start - p < 9 || !in_.read(reinterpret_cast<char*>(head), 9)) return false;
    const std::uint64_t len = le64(head + 1);
    if (len > summary_start - p - 9) return false;
    if (head[0] == kMessage) return false;
    if (head[0] == kSchema || head[0] == kChannel || head[0] == kHeader) {
      content.resize(static_cast<std::size_t>(len));
      if (len > 0 && !in_.read(reinterpret_cast<char*>(content.data()), static_cast<std::streamsize>(len)))
        return false;
      try {
        handle(head[0], content, p, false);
      } catch (const std::exception&) {
        return false;
      }
    }
    if (head[0] == kDataEnd) break;
    p += 9 + len;
  }
  std::stable_sort(merge->order.begin(), merge->order.end(),
                   [](const Merge::Chunk& a, const Merge::Chunk& b) { return a.start < b.start; });
  merge_ = std::move(merge);
  return true;
}

bool McapReader::nextMerged(LogMessage& out) {
  Merge& g = *merge_;
  g.last.reset();
  for (;;) {
    // The open chunk with the earliest next message (the earliest opened among equal times).
    Merge::Open* best = nullptr;
    for (const auto& o : g.open)
      if (!best || o->messages[o->next].log_time < best->messages[best->next].log_time) best = o.get();
    const bool more = g.opened < g.order.size();
    if (more && (!best || g.order[g.opened].start <= best->messages[best->next].log_time)) {
      // Open the next chunk by start time: its schemas and channels taken, its messages sorted.
      const Merge::Chunk& c = g.order[g.opened++];
      auto o = std::make_unique<Merge::Open>();
      o->at = c.offset;
      std::vector<std::uint8_t> record(static_cast<std::size_t>(c.length));
      in_.clear();
      in_.seekg(static_cast<std::streamoff>(c.offset));
      if (!in_.read(reinterpret_cast<char*>(record.data()), static_cast<std::streamsize>(record.size())) ||
          record[0] != kChunk)
        fail(c.offset, "the chunk index points at no Chunk record here");
      if (le64(record.data() + 1) != c.length - 9)
        fail(c.offset, "the chunk index gives this chunk another length than its record");
      try {
        decompressChunk(std::span<const std::uint8_t>(record).subspan(9), c.offset, o->records);
      } catch (const std::out_of_range& e) {
        fail(c.offset, e.what());
      }
      for (std::size_t p = 0; p < o->records.size();) {
        std::uint8_t op = 0;
        const std::span<const std::uint8_t> content = chunkRecord(o->records, p, c.offset, op);
        if (op == kMessage) {
          if (content.size() < 22)
            fail(c.offset,
                 "the Message record is too short for its header (" + std::to_string(content.size()) + " bytes)");
          const std::size_t at = static_cast<std::size_t>(content.data() - o->records.data());
          o->messages.push_back({le64(content.data() + 6), at, content.size()});
        } else if (op == kSchema || op == kChannel) {
          handle(op, content, c.offset, true);
        }
      }
      std::stable_sort(o->messages.begin(), o->messages.end(),
                       [](const Merge::Entry& a, const Merge::Entry& b) { return a.log_time < b.log_time; });
      if (!o->messages.empty()) g.open.push_back(std::move(o));
      continue;
    }
    if (!best) return false;
    const Merge::Entry e = best->messages[best->next++];
    chunk_at_ = best->at;
    handle(kMessage, std::span<const std::uint8_t>(best->records.data() + e.record, e.size), best->at, true);
    pending_ = false;
    out = message_;
    if (best->next == best->messages.size()) {  // done: kept until the caller has the message's bytes
      const auto it = std::find_if(g.open.begin(), g.open.end(), [&](const auto& o) { return o.get() == best; });
      g.last = std::move(*it);
      g.open.erase(it);
    }
    return true;
  }
}

void McapReader::fail(std::uint64_t at, const std::string& problem) const {
  throw InputError(InputLocation{path_, 0, 0, "byte " + std::to_string(at)}, problem);
}

void McapReader::cut(std::uint64_t at, const std::string& where) {
  damage_ = "cut short at byte " + std::to_string(at) + " of " + std::to_string(size_) + " (" + where + ")";
  ended_ = true;
}

bool McapReader::readRecord(std::uint8_t& opcode, std::vector<std::uint8_t>& content, std::uint64_t& at) {
  at = pos_;
  if (size_ - pos_ < 9) {
    if (size_ - pos_ == 8 && in_summary_ == false) {  // the closing magic without a footer
      cut(pos_, "no Footer record before the closing magic");
      return false;
    }
    cut(pos_, pos_ == size_ ? "no Footer record: the recording did not finish" : "inside a record's opcode and length");
    return false;
  }
  std::uint8_t head[9];
  in_.read(reinterpret_cast<char*>(head), 9);
  opcode = head[0];
  const std::uint64_t len = le64(head + 1);
  if (len > size_ - pos_ - 9) {  // never allocated beyond what the file holds
    cut(pos_, std::string("inside a ") + opName(opcode) + " record of " + std::to_string(len) + " bytes");
    return false;
  }
  content.resize(static_cast<std::size_t>(len));
  if (len > 0 && !in_.read(reinterpret_cast<char*>(content.data()), static_cast<std::streamsize>(len)))
    fail(pos_, "cannot be read");
  if (data_crc_on_ && opcode != kDataEnd)
    data_crc_ = crc32Of(crc32Of(data_crc_, head, 9), content.data(), content.size());
  if (in_summary_) {
    // The summary CRC runs up to the footer's summary_crc field (its last 4 bytes).
    const std::size_t counted = opcode == kFooter && content.size() >= 4 ? content.size() - 4 : content.size();
    summary_crc_ = crc32Of(crc32Of(summary_crc_, head, 9), content.data(), counted);
  }
  pos_ += 9 + len;
  return true;
}

std::span<const std::uint8_t> McapReader::chunkRecord(const std::vector<std::uint8_t>& records, std::size_t& pos,
                                                      std::uint64_t at, std::uint8_t& op) const {
  const std::size_t left = records.size() - pos;
  if (left < 9) fail(at, "the chunk ends inside a record's opcode and length");
  op = records[pos];
  const std::uint64_t len = le64(records.data() + pos + 1);
  if (len > left - 9) fail(at, std::string("a ") + opName(op) + " record inside the chunk runs past its end");
  if (op != kSchema && op != kChannel && op != kMessage && op <= kDataEnd)
    fail(at,
         std::string("a ") + opName(op) + " record inside a chunk (only schemas, channels and messages belong there)");
  const std::span<const std::uint8_t> content(records.data() + pos + 9, static_cast<std::size_t>(len));
  pos += 9 + static_cast<std::size_t>(len);
  return content;
}

void McapReader::openChunk(std::span<const std::uint8_t> content, std::uint64_t at) {
  decompressChunk(content, at, chunk_);
  chunk_at_ = at;
  chunk_pos_ = 0;
}

void McapReader::decompressChunk(std::span<const std::uint8_t> content, std::uint64_t at,
                                 std::vector<std::uint8_t>& chunk) {
  std::vector<std::uint8_t>& chunk_ = chunk;
  Fields f(content, "Chunk");
  f.num<std::uint64_t>("message_start_time");
  f.num<std::uint64_t>("message_end_time");
  const std::uint64_t size = f.num<std::uint64_t>("uncompressed_size");
  const std::uint32_t crc = f.num<std::uint32_t>("uncompressed_crc");
  const std::string compression = f.str("compression");
  const std::span<const std::uint8_t> records = f.bytes64("records");
  if (size > kMaxChunk)
    fail(at, "a chunk of " + std::to_string(size) + " bytes uncompressed, more than this reader takes (2 GiB)");
  chunk_.clear();
  if (const std::string problem = detail::takeFromBudget(decompress_left_, size); !problem.empty()) fail(at, problem);
  if (compression.empty()) {
    if (records.size() != size)
      fail(at, "an uncompressed chunk of " + std::to_string(records.size()) + " bytes says it holds " +
                   std::to_string(size));
    chunk_.assign(records.begin(), records.end());
  } else if (compression == "zstd" || compression == "lz4") {
    // Streamed: the buffer grows with what the data really decompresses to, not with the claim.
    const std::string problem = detail::decompress(compression, records, size, chunk_);
    if (!problem.empty()) fail(at, problem);
  } else {
    fail(at, "the chunk's compression '" + printable(compression, 40) + "' is not none, zstd or lz4");
  }
  if (crc != 0 && crc32Of(0, chunk_.data(), chunk_.size()) != crc)
    fail(at, "the chunk's CRC does not match its records (damaged)");
  ++chunks_[compression.empty() ? "none" : compression];
}

void McapReader::handle(std::uint8_t opcode, std::span<const std::uint8_t> content, std::uint64_t at, bool in_chunk) {
  try {
    switch (opcode) {
      case kHeader: {
        Fields f(content, "Header");
        profile_ = f.str("profile");
        library_ = f.str("library");
        break;
      }
      case kSchema: {
        Fields f(content, "Schema");
        Schema s;
        s.id = f.num<std::uint16_t>("id");
        s.name = f.str("name");
        s.encoding = f.str("encoding");
        const auto d = f.bytes32("data");
        s.data.assign(reinterpret_cast<const char*>(d.data()), d.size());
        if (s.id == 0) fail(at, "a Schema record with id 0 (reserved for 'no schema')");
        const auto it = schemas_.find(s.id);
        if (it != schemas_.end() &&
            (it->second.name != s.name || it->second.encoding != s.encoding || it->second.data != s.data))
          fail(at, "schema " + std::to_string(s.id) + " is defined twice, differently");
        schemas_[s.id] = std::move(s);
        break;
      }
      case kChannel: {
        Fields f(content, "Channel");
        Channel c;
        c.id = f.num<std::uint16_t>("id");
        c.schema_id = f.num<std::uint16_t>("schema_id");
        c.topic = f.str("topic");
        c.message_encoding = f.str("message_encoding");
        const auto map = f.bytes32("metadata");
        Fields m(map, "Channel metadata");
        while (m.position() < map.size()) {
          std::string k = m.str("metadata key");
          c.metadata.emplace_back(std::move(k), m.str("metadata value"));
        }
        if (c.schema_id != 0 && !schemas_.count(c.schema_id))
          fail(at, "channel " + std::to_string(c.id) + " (" + printable(c.topic, 60) + ") names schema " +
                       std::to_string(c.schema_id) + ", which no earlier record defines");
        const auto it = channels_.find(c.id);
        if (it != channels_.end() && (it->second.topic != c.topic || it->second.schema_id != c.schema_id ||
                                      it->second.message_encoding != c.message_encoding))
          fail(at, "channel " + std::to_string(c.id) + " is defined twice, differently");
        channels_[c.id] = std::move(c);
        break;
      }
      case kMessage: {
        if (in_summary_) fail(at, "a Message record after the Data End record");
        Fields f(content, "Message");
        LogMessage& m = message_;
        const std::uint16_t channel = f.num<std::uint16_t>("channel_id");
        m.sequence = f.num<std::uint32_t>("sequence");
        m.log_time = f.num<std::uint64_t>("log_time");
        m.publish_time = f.num<std::uint64_t>("publish_time");
        m.data = f.rest();
        const auto c = channels_.find(channel);
        if (c == channels_.end())
          fail(at, "a message on channel " + std::to_string(channel) + ", which no earlier record defines");
        m.channel = &c->second;
        m.schema = nullptr;
        if (c->second.schema_id != 0) m.schema = &schemas_.at(c->second.schema_id);
        m.offset = in_chunk ? chunk_at_ : at;
        pending_ = true;
        break;
      }
      case kChunk:
        if (in_chunk) fail(at, "a Chunk inside a chunk");
        if (in_summary_) fail(at, "a Chunk record after the Data End record");
        openChunk(content, at);
        break;
      case kDataEnd: {
        Fields f(content, "Data End");
        const std::uint32_t crc = f.num<std::uint32_t>("data_section_crc");
        if (crc != 0 && crc != data_crc_) fail(at, "the data section's CRC does not match (damaged)");
        data_crc_on_ = false;
        in_summary_ = true;
        summary_crc_ = 0;
        break;
      }
      case kFooter: {
        Fields f(content, "Footer");
        const std::uint64_t summary_start = f.num<std::uint64_t>("summary_start");
        f.num<std::uint64_t>("summary_offset_start");
        const std::uint32_t crc = f.num<std::uint32_t>("summary_crc");
        if (crc != 0 && summary_start != 0 && crc != summary_crc_)
          fail(at, "the summary section's CRC does not match (damaged)");
        ended_ = true;
        break;
      }
      default:
        break;  // indexes, statistics, attachments, metadata and records of later versions: not needed to read the
                // messages
    }
  } catch (const std::out_of_range& e) {
    fail(at, e.what());
  }
}

bool McapReader::next(LogMessage& out) {
  if (merge_) return nextMerged(out);
  for (;;) {
    if (pending_) {
      pending_ = false;
      out = message_;
      return true;
    }
    // Records of the open chunk first.
    if (chunk_pos_ < chunk_.size()) {
      std::uint8_t op = 0;
      const std::span<const std::uint8_t> content = chunkRecord(chunk_, chunk_pos_, chunk_at_, op);
      handle(op, content, chunk_at_, true);
      continue;
    }
    if (ended_) return false;
    std::uint8_t op = 0;
    std::uint64_t at = 0;
    if (!readRecord(op, record_, at)) return false;
    if (at == 8 && op != kHeader) fail(at, "the first record is a " + std::string(opName(op)) + ", not the Header");
    handle(op, record_, at, false);
    if (op == kFooter) {
      // The closing magic.
      std::uint8_t magic[8] = {};
      if (size_ - pos_ < 8 || !in_.read(reinterpret_cast<char*>(magic), 8) || std::memcmp(magic, kMagic, 8) != 0)
        cut(pos_, "no closing magic after the Footer");
      return false;
    }
  }
}

namespace {

constexpr std::uint64_t kByteBits = 48;  // a split bag's offsets: the file's index above, the byte below

// `s` with its length in front: pieces joined this way cannot run into one another.
void appendPiece(std::string& key, const std::string& s) {
  key += std::to_string(s.size());
  key += ':';
  key += s;
}

}  // namespace

SplitMcapReader::SplitMcapReader(std::vector<std::string> files, std::string label)
    : files_(std::move(files)), label_(std::move(label)) {
  if (files_.empty()) throw InputError(InputLocation{label_, 0, 0, "folder"}, "no MCAP file");
  // Every file before the first message: a missing one is an error now, not after part of the log.
  for (const std::string& f : files_) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(f, ec))
      throw InputError(InputLocation{f, 0, 0, "file"}, "listed in the folder's metadata.yaml, but not a file there");
  }
  open(0);
}

SplitMcapReader::~SplitMcapReader() = default;

void SplitMcapReader::open(std::size_t file) {
  if (file == 1) profile_ = reader_->profile(), library_ = reader_->library();
  if (reader_)
    for (const auto& [compression, n] : reader_->chunks()) chunks_[compression] += n;
  reader_.reset();  // one file open at a time
  file_ = file;
  file_channels_.clear();
  reader_ = std::make_unique<McapReader>(files_[file]);
}

std::string SplitMcapReader::profile() const { return file_ == 0 ? reader_->profile() : profile_; }
std::string SplitMcapReader::library() const { return file_ == 0 ? reader_->library() : library_; }

std::map<std::string, int> SplitMcapReader::chunks() const {
  std::map<std::string, int> all = chunks_;
  for (const auto& [compression, n] : reader_->chunks()) all[compression] += n;
  return all;
}

std::string SplitMcapReader::place(std::uint64_t offset) const {
  const std::uint64_t file = offset >> kByteBits, byte = offset & ((std::uint64_t{1} << kByteBits) - 1);
  return std::filesystem::path(files_[std::min<std::size_t>(file, files_.size() - 1)]).filename().string() + " byte " +
         std::to_string(byte);
}

const Channel& SplitMcapReader::channelOf(const LogMessage& m) {
  if (const auto it = file_channels_.find(m.channel->id); it != file_channels_.end()) return channels_.at(it->second);
  std::string key;
  for (const std::string* piece : {&m.channel->topic, &m.channel->message_encoding}) appendPiece(key, *piece);
  for (const auto& [k, v] : m.channel->metadata) appendPiece(key, k), appendPiece(key, v);
  key += m.schema ? "schema" : "none";
  if (m.schema)
    for (const std::string* piece : {&m.schema->name, &m.schema->encoding, &m.schema->data}) appendPiece(key, *piece);
  auto [it, fresh] = channel_of_key_.try_emplace(key, static_cast<std::uint16_t>(channels_.size() + 1));
  if (fresh) {
    if (channels_.size() >= 65000)
      throw InputError(InputLocation{files_[file_], 0, 0, "byte " + std::to_string(m.offset)},
                       "more than 65000 channels in the bag's files");
    Channel c = *m.channel;
    c.id = c.schema_id = it->second;
    if (m.schema) {
      Schema s = *m.schema;
      s.id = c.id;
      schemas_[s.id] = std::move(s);
    } else {
      c.schema_id = 0;
    }
    channels_[c.id] = std::move(c);
  }
  file_channels_[m.channel->id] = it->second;
  return channels_.at(it->second);
}

bool SplitMcapReader::next(LogMessage& out) {
  while (!done_) {
    if (reader_->next(out)) {
      const Channel& c = channelOf(out);
      out.channel = &c;
      out.schema = c.schema_id ? &schemas_.at(c.schema_id) : nullptr;
      out.offset =
          (static_cast<std::uint64_t>(file_) << kByteBits) | (out.offset & ((std::uint64_t{1} << kByteBits) - 1));
      return true;
    }
    if (!reader_->damage().empty())
      damage_ += (damage_.empty() ? "" : "; ") + std::filesystem::path(files_[file_]).filename().string() + ": " +
                 reader_->damage();
    if (file_ + 1 < files_.size())
      open(file_ + 1);
    else
      done_ = true;
  }
  return false;
}

}  // namespace kccd::logs
