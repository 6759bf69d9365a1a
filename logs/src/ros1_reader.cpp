#include "kccd/logs/ros1_reader.hpp"

#include <algorithm>
#include <cstring>

#include <bzlib.h>
#include <lz4frame.h>

#include "decompress.hpp"
#include "kccd/input_error.hpp"

namespace kccd::logs {
namespace {

constexpr char kRos1Magic[] = "#ROSBAG V2.0\n";
constexpr std::uint64_t kMaxRos1Chunk = std::uint64_t{1} << 31;
enum : std::uint8_t {
  kOpMessage = 0x02,
  kOpBagHeader = 0x03,
  kOpIndex = 0x04,
  kOpChunk = 0x05,
  kOpChunkInfo = 0x06,
  kOpConnection = 0x07
};

std::uint32_t le32(const std::uint8_t* p) {
  return std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 | std::uint32_t(p[3]) << 24;
}

// A record header's (or connection header's) fields: "name=value" each after a 32-bit length.
std::map<std::string, std::string> fieldsOf(std::span<const std::uint8_t> h, std::string& problem) {
  std::map<std::string, std::string> f;
  std::size_t i = 0;
  while (i < h.size()) {
    if (h.size() - i < 4) {
      problem = "a header field's length is cut";
      return f;
    }
    const std::uint32_t n = le32(h.data() + i);
    i += 4;
    if (n > h.size() - i) {
      problem = "a header field of " + std::to_string(n) + " bytes runs past its header";
      return f;
    }
    const std::string_view field(reinterpret_cast<const char*>(h.data() + i), n);
    i += n;
    const std::size_t eq = field.find('=');
    if (eq == std::string_view::npos) {
      problem = "a header field without '='";
      return f;
    }
    f[std::string(field.substr(0, eq))] = std::string(field.substr(eq + 1));
  }
  return f;
}

template <class T>
bool numberOf(const std::map<std::string, std::string>& f, const char* name, T& out) {
  const auto it = f.find(name);
  if (it == f.end() || it->second.size() != sizeof(T)) return false;
  out = 0;
  for (std::size_t k = 0; k < sizeof(T); ++k)
    out |= static_cast<T>(static_cast<T>(static_cast<std::uint8_t>(it->second[k])) << (8 * k));
  return true;
}

// What the bytes of a compressed chunk cut short decompress to: the longest prefix the streaming
// decoder gives (at most `size` bytes: the chunk's declared size), so a reader keeps the records
// it holds whole. LZ4 frames give each whole block, bzip2 each whole block of up to 900 kB; a
// stream that does not decode gives nothing, since a bad block's bytes may already be out.
std::vector<std::uint8_t> lz4Prefix(std::span<const std::uint8_t> in, std::uint64_t size) {
  constexpr std::size_t kStep = std::size_t{1} << 20;
  std::vector<std::uint8_t> out;
  LZ4F_dctx* z = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&z, LZ4F_VERSION))) return out;
  // Called on with no input left too: a block decoded from the last bytes may still be flushing.
  for (std::size_t used = 0; out.size() < size;) {
    const std::size_t have = out.size();
    std::size_t made = static_cast<std::size_t>(std::min<std::uint64_t>(size - have, kStep)), took = in.size() - used;
    out.resize(have + made);
    const std::size_t ret = LZ4F_decompress(z, out.data() + have, &made, in.data() + used, &took, nullptr);
    if (LZ4F_isError(ret)) {
      out.clear();
      break;
    }
    out.resize(have + made);
    used += took;
    if (ret == 0 || (took == 0 && made == 0)) break;
  }
  LZ4F_freeDecompressionContext(z);
  return out;
}

std::vector<std::uint8_t> bz2Prefix(std::span<const std::uint8_t> in, std::uint64_t size) {
  constexpr std::size_t kStep = std::size_t{1} << 20;
  std::vector<std::uint8_t> out;
  bz_stream s{};
  if (BZ2_bzDecompressInit(&s, 0, 0) != BZ_OK) return out;
  s.next_in = const_cast<char*>(reinterpret_cast<const char*>(in.data()));
  s.avail_in = static_cast<unsigned>(std::min<std::size_t>(in.size(), 0xffffffffu));
  while (out.size() < size) {
    const std::size_t have = out.size();
    const std::size_t room = static_cast<std::size_t>(std::min<std::uint64_t>(size - have, kStep));
    out.resize(have + room);
    s.next_out = reinterpret_cast<char*>(out.data() + have);
    s.avail_out = static_cast<unsigned>(room);
    const int ret = BZ2_bzDecompress(&s);
    out.resize(have + room - s.avail_out);
    if (ret != BZ_OK && ret != BZ_STREAM_END) {
      out.clear();
      break;
    }
    if (ret == BZ_STREAM_END || (s.avail_out == room && s.avail_in == 0)) break;
  }
  BZ2_bzDecompressEnd(&s);
  return out;
}

}  // namespace

Ros1Reader::Ros1Reader(const std::string& path) : path_(path) {
  in_.open(path, std::ios::binary);
  if (!in_) throw InputError(InputLocation{path, 0, 0, "file"}, "cannot be opened");
  in_.seekg(0, std::ios::end);
  size_ = static_cast<std::uint64_t>(std::max<std::streamoff>(in_.tellg(), 0));
  decompress_left_ = detail::decompressBudget(size_);
  in_.seekg(0);
  char magic[13] = {};
  if (size_ < 13 || !in_.read(magic, 13) || std::memcmp(magic, kRos1Magic, 13) != 0)
    throw InputError(InputLocation{path, 0, 0, "byte 0"},
                     "not a ROS 1 bag of format 2.0 (its first line is not #ROSBAG V2.0)");
  pos_ = 13;
}

Ros1Reader::~Ros1Reader() = default;

void Ros1Reader::fail(std::uint64_t at, const std::string& problem) const {
  throw InputError(InputLocation{path_, 0, 0, "byte " + std::to_string(at)}, problem);
}

bool Ros1Reader::record(std::span<const std::uint8_t> header, std::span<const std::uint8_t> data, std::uint64_t at,
                        bool in_chunk) {
  std::string problem;
  const auto f = fieldsOf(header, problem);
  if (!problem.empty()) fail(at, problem);
  std::uint8_t op = 0;
  if (!numberOf(f, "op", op)) fail(at, "a record without its op field");
  switch (op) {
    case kOpConnection: {
      std::uint32_t conn = 0;
      if (!numberOf(f, "conn", conn) || !f.count("topic")) fail(at, "a connection record without conn and topic");
      std::string cproblem;
      const auto c = fieldsOf(data, cproblem);
      if (!cproblem.empty()) fail(at, "connection " + std::to_string(conn) + ": " + cproblem);
      if (channel_of_conn_.count(conn)) break;  // repeated in the index section
      if (channels_.size() >= 65000) fail(at, "more than 65000 connections");
      const auto id = static_cast<std::uint16_t>(channels_.size() + 1);
      channel_of_conn_[conn] = id;
      Channel ch;
      ch.id = id;
      ch.topic = f.at("topic");
      ch.message_encoding = "ros1";
      if (const auto t = c.find("type"); t != c.end()) {
        Schema s;
        s.id = id;
        s.name = t->second;
        s.encoding = "ros1msg";
        if (const auto d = c.find("message_definition"); d != c.end()) s.data = d->second;
        schemas_[id] = s;
        ch.schema_id = id;
      }
      for (const char* k : {"md5sum", "callerid", "latching"})
        if (const auto v = c.find(k); v != c.end()) ch.metadata.emplace_back(k, v->second);
      channels_[id] = ch;
      break;
    }
    case kOpMessage: {
      std::uint32_t conn = 0;
      std::uint64_t time = 0;
      if (!numberOf(f, "conn", conn) || !numberOf(f, "time", time)) fail(at, "a message record without conn and time");
      const auto c = channel_of_conn_.find(conn);
      if (c == channel_of_conn_.end())
        fail(at, "a message on connection " + std::to_string(conn) + ", which no earlier record defines");
      const Channel& ch = channels_.at(c->second);
      message_.channel = &ch;
      message_.schema = ch.schema_id ? &schemas_.at(ch.schema_id) : nullptr;
      message_.sequence = 0;
      // ROS time: seconds then nanoseconds, 32 bits each.
      message_.log_time = message_.publish_time = (time & 0xffffffffu) * 1000000000ull + (time >> 32);
      message_.data = data;
      message_.offset = in_chunk ? chunk_at_ : at;
      return true;
    }
    case kOpChunk: {
      if (in_chunk) fail(at, "a chunk inside a chunk");
      std::uint32_t size = 0;
      const auto comp = f.find("compression");
      if (comp == f.end() || !numberOf(f, "size", size)) fail(at, "a chunk record without compression and size");
      if (size > kMaxRos1Chunk) fail(at, "a chunk of " + std::to_string(size) + " bytes");
      if (const std::string problem = detail::takeFromBudget(decompress_left_, size); !problem.empty())
        fail(at, problem);
      if (comp->second == "none") {
        if (data.size() != size)
          fail(at, "an uncompressed chunk of " + std::to_string(data.size()) + " bytes says it holds " +
                       std::to_string(size));
        chunk_.assign(data.begin(), data.end());
      } else if (comp->second == "bz2" || comp->second == "lz4") {
        const std::string p = detail::decompress(comp->second, data, size, chunk_);
        if (!p.empty()) fail(at, p);
      } else {
        fail(at, "the chunk's compression '" + printable(comp->second, 40) + "' is not none, bz2 or lz4");
      }
      ++chunks_[comp->second];
      chunk_at_ = at;
      chunk_pos_ = 0;
      chunk_cut_ = false;
      break;
    }
    case kOpBagHeader:
      if (!numberOf(f, "index_pos", index_pos_) || !numberOf(f, "chunk_count", chunk_count_))
        fail(at, "a bag header without index_pos and chunk_count");
      have_header_ = true;
      break;
    case kOpChunkInfo:
      ++chunk_infos_;
      break;
    default:
      break;  // index data: not needed to read the messages
  }
  return false;
}

std::string Ros1Reader::openCutChunk(std::uint64_t at, std::uint32_t declared) {
  std::string problem;
  const auto f = fieldsOf(header_, problem);
  std::uint8_t op = 0;
  std::uint32_t size = 0;
  const auto comp = f.find("compression");
  if (!problem.empty() || !numberOf(f, "op", op) || op != kOpChunk || comp == f.end() || !numberOf(f, "size", size) ||
      size > kMaxRos1Chunk || !detail::takeFromBudget(decompress_left_, size).empty())
    return {};  // not a chunk, or one that says nothing this reader believes
  const std::string& compression = comp->second;
  if (compression != "none" && compression != "bz2" && compression != "lz4") return {};
  if (compression == "none" && size != declared) return {};
  data_.resize(static_cast<std::size_t>(size_ - pos_ - 8 - header_.size()));
  in_.read(reinterpret_cast<char*>(data_.data()), static_cast<std::streamsize>(data_.size()));
  data_.resize(static_cast<std::size_t>(std::max<std::streamsize>(in_.gcount(), 0)));
  if (compression == "none")
    chunk_ = data_;
  else
    chunk_ = compression == "lz4" ? lz4Prefix(data_, size) : bz2Prefix(data_, size);
  chunk_at_ = at;
  chunk_pos_ = 0;
  chunk_cut_ = true;
  if (compression == "none") {
    ++chunks_[compression];
    return ": an uncompressed chunk: its records whole before the cut are read";
  }
  // Decoders give whole blocks only (LZ4 frames' of up to 4 MB, bzip2's of up to 900 kB).
  if (chunk_.empty())
    return ": a chunk compressed with " + compression + " of which nothing decompresses before the cut, " +
           compression + " giving whole blocks only: none of its messages are read";
  ++chunks_[compression];
  return ": a chunk compressed with " + compression + " whose first " + std::to_string(chunk_.size()) + " of " +
         std::to_string(size) + " bytes decompress before the cut, " + compression +
         " giving whole blocks: the records whole in them are read";
}

bool Ros1Reader::next(LogMessage& out) {
  for (;;) {
    // The open chunk's records first.
    while (chunk_pos_ < chunk_.size()) {
      const std::size_t left = chunk_.size() - chunk_pos_;
      const std::uint32_t hl = left < 4 ? 0 : le32(chunk_.data() + chunk_pos_);
      const bool whole = left >= 4 && hl <= left - 4 && left - 4 - hl >= 4 &&
                         le32(chunk_.data() + chunk_pos_ + 4 + hl) <= left - 8 - hl;
      if (!whole && chunk_cut_) {  // the rest of a chunk cut short: past the cut
        chunk_pos_ = chunk_.size();
        break;
      }
      if (left < 4) fail(chunk_at_, "the chunk ends inside a record's header length");
      if (!whole) fail(chunk_at_, "a record inside the chunk runs past its end");
      const std::uint32_t dl = le32(chunk_.data() + chunk_pos_ + 4 + hl);
      const std::span<const std::uint8_t> h(chunk_.data() + chunk_pos_ + 4, hl),
          d(chunk_.data() + chunk_pos_ + 8 + hl, dl);
      chunk_pos_ += 8 + hl + dl;
      if (record(h, d, chunk_at_, true)) {
        out = message_;
        return true;
      }
    }
    if (ended_) return false;
    const std::uint64_t at = pos_;
    auto cut = [&](const std::string& where) {
      damage_ = "cut short at byte " + std::to_string(at) + " of " + std::to_string(size_) + " (" + where + ")";
      ended_ = true;
    };
    if (pos_ == size_) {
      // A bag ends after its index: a cut at a record's end shows as a missing index or part of it.
      if (!have_header_)
        cut("no bag header record");
      else if (index_pos_ == 0)
        damage_ = "not closed: the bag header points at no index (the recording stopped before the bag was closed)";
      else if (size_ <= index_pos_)
        cut("before its index at byte " + std::to_string(index_pos_));
      else if (chunk_infos_ < chunk_count_)
        cut("its index lists " + std::to_string(chunk_infos_) + " of its " + std::to_string(chunk_count_) + " chunks");
      ended_ = true;
      return false;
    }
    std::uint8_t len[4];
    if (size_ - pos_ < 4 || !in_.read(reinterpret_cast<char*>(len), 4)) {
      cut("inside a record's header length");
      return false;
    }
    const std::uint32_t hl = le32(len);
    if (hl > size_ - pos_ - 4) {
      cut("inside a record header of " + std::to_string(hl) + " bytes");
      return false;
    }
    header_.resize(hl);
    in_.read(reinterpret_cast<char*>(header_.data()), hl);
    if (size_ - pos_ - 4 - hl < 4 || !in_.read(reinterpret_cast<char*>(len), 4)) {
      cut("inside a record's data length");
      return false;
    }
    const std::uint32_t dl = le32(len);
    if (dl > size_ - pos_ - 8 - hl) {
      cut("inside a record's " + std::to_string(dl) + " bytes of data" + openCutChunk(at, dl));
      continue;  // the whole records of a chunk cut short, then the end
    }
    data_.resize(dl);
    in_.read(reinterpret_cast<char*>(data_.data()), dl);
    pos_ += 8 + hl + dl;
    if (record(header_, data_, at, false)) {
      out = message_;
      return true;
    }
  }
}

}  // namespace kccd::logs
