#include "decompress.hpp"

#include <algorithm>

#include <bzlib.h>
#include <lz4frame.h>
#include <snappy-c.h>
#include <zlib.h>
#include <zstd.h>

namespace kccd::logs::detail {
namespace {

constexpr std::size_t kStep = std::size_t{1} << 20;  // the buffer grows by at most this per call

std::string sizeMismatch(const std::string& what, const char* unit, std::size_t got, std::uint64_t size,
                         bool complete) {
  return "the " + what + " " + unit + " decompresses to " + std::to_string(got) + " bytes, not the " +
         std::to_string(size) + " it declares" + (complete ? "" : " (its data is not complete)");
}

std::string zstd(std::span<const std::uint8_t> in, std::uint64_t size, std::vector<std::uint8_t>& out,
                 const char* unit) {
  ZSTD_DCtx* z = ZSTD_createDCtx();
  if (!z) return "zstd: out of memory";
  ZSTD_inBuffer inb{in.data(), in.size(), 0};
  std::size_t ret = 1;
  for (;;) {
    const std::size_t have = out.size();
    std::uint8_t probe[1];
    // Past the declared size only a probe byte is offered: any output there is a mismatch.
    const bool full = have >= size;
    if (!full) out.resize(have + static_cast<std::size_t>(std::min<std::uint64_t>(size - have, kStep)));
    ZSTD_outBuffer o{full ? probe : out.data() + have, full ? 1 : out.size() - have, 0};
    ret = ZSTD_decompressStream(z, &o, &inb);
    if (full) {
      if (o.pos > 0) out.push_back(probe[0]);
    } else {
      out.resize(have + o.pos);
    }
    if (ZSTD_isError(ret) || ret == 0 || (full && o.pos > 0)) break;
    if (o.pos == 0 && inb.pos == inb.size) break;  // the input ended first
  }
  ZSTD_freeDCtx(z);
  if (ZSTD_isError(ret)) return std::string("the zstd ") + unit + " does not decompress: " + ZSTD_getErrorName(ret);
  if (ret != 0 || out.size() != size) return sizeMismatch("zstd", unit, out.size(), size, ret == 0);
  return {};
}

std::string lz4(std::span<const std::uint8_t> in, std::uint64_t size, std::vector<std::uint8_t>& out,
                const char* unit) {
  LZ4F_dctx* z = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&z, LZ4F_VERSION))) return "lz4: out of memory";
  const std::uint8_t* src = in.data();
  std::size_t left = in.size(), ret = 1;
  std::string error;
  while (left > 0 && ret != 0) {
    const std::size_t have = out.size();
    std::uint8_t probe[1];
    const bool full = have >= size;
    std::size_t out_size = full ? 1 : static_cast<std::size_t>(std::min<std::uint64_t>(size - have, kStep));
    if (!full) out.resize(have + out_size);
    std::size_t in_size = left;
    ret = LZ4F_decompress(z, full ? probe : out.data() + have, &out_size, src, &in_size, nullptr);
    if (LZ4F_isError(ret)) {
      error = std::string("the lz4 ") + unit + " does not decompress: " + LZ4F_getErrorName(ret);
      if (!full) out.resize(have);
      break;
    }
    if (full) {
      if (out_size > 0) {
        out.push_back(probe[0]);
        break;
      }
    } else {
      out.resize(have + out_size);
    }
    src += in_size, left -= in_size;
    if (in_size == 0 && out_size == 0) break;
  }
  LZ4F_freeDecompressionContext(z);
  if (!error.empty()) return error;
  if (ret != 0 || out.size() != size) return sizeMismatch("lz4", unit, out.size(), size, ret == 0);
  return {};
}

std::string bz2(std::span<const std::uint8_t> in, std::uint64_t size, std::vector<std::uint8_t>& out,
                const char* unit) {
  bz_stream s{};
  if (BZ2_bzDecompressInit(&s, 0, 0) != BZ_OK) return "bz2: out of memory";
  s.next_in = const_cast<char*>(reinterpret_cast<const char*>(in.data()));
  s.avail_in = static_cast<unsigned>(std::min<std::size_t>(in.size(), 0xffffffffu));
  int ret = BZ_OK;
  for (;;) {
    const std::size_t have = out.size();
    char probe[1];
    const bool full = have >= size;
    const std::size_t room = full ? 1 : static_cast<std::size_t>(std::min<std::uint64_t>(size - have, kStep));
    if (!full) out.resize(have + room);
    s.next_out = full ? probe : reinterpret_cast<char*>(out.data() + have);
    s.avail_out = static_cast<unsigned>(room);
    ret = BZ2_bzDecompress(&s);
    const std::size_t made = room - s.avail_out;
    if (full) {
      if (made > 0) out.push_back(static_cast<std::uint8_t>(probe[0]));
    } else {
      out.resize(have + made);
    }
    if (ret != BZ_OK || (full && made > 0)) break;
    if (made == 0 && s.avail_in == 0) break;
  }
  BZ2_bzDecompressEnd(&s);
  if (ret != BZ_OK && ret != BZ_STREAM_END)
    return std::string("the bz2 ") + unit + " does not decompress (bzip2 error " + std::to_string(ret) + ")";
  if (ret != BZ_STREAM_END || out.size() != size)
    return sizeMismatch("bz2", unit, out.size(), size, ret == BZ_STREAM_END);
  return {};
}

std::string gzip(std::span<const std::uint8_t> in, std::uint64_t size, std::vector<std::uint8_t>& out,
                 const char* unit) {
  z_stream s{};
  if (inflateInit2(&s, 15 + 32) != Z_OK) return "gzip: out of memory";  // +32: a gzip or a zlib header
  s.next_in = const_cast<Bytef*>(in.data());
  s.avail_in = static_cast<uInt>(std::min<std::size_t>(in.size(), 0xffffffffu));
  int ret = Z_OK;
  for (;;) {
    const std::size_t have = out.size();
    std::uint8_t probe[1];
    const bool full = have >= size;
    const std::size_t room = full ? 1 : static_cast<std::size_t>(std::min<std::uint64_t>(size - have, kStep));
    if (!full) out.resize(have + room);
    s.next_out = full ? probe : out.data() + have;
    s.avail_out = static_cast<uInt>(room);
    ret = inflate(&s, Z_NO_FLUSH);
    const std::size_t made = room - s.avail_out;
    if (full) {
      if (made > 0) out.push_back(probe[0]);
    } else {
      out.resize(have + made);
    }
    // Writers may join gzip members: the next one starts where a stream ends.
    if (ret == Z_STREAM_END && s.avail_in >= 2 && s.next_in[0] == 0x1f && s.next_in[1] == 0x8b && !(full && made > 0)) {
      if (inflateReset(&s) != Z_OK) break;
      ret = Z_OK;
      continue;
    }
    if (ret != Z_OK || (full && made > 0)) break;
    if (made == 0 && s.avail_in == 0) break;
  }
  inflateEnd(&s);
  // Z_BUF_ERROR: the input ended before the stream did (reported as data that is not complete).
  if (ret != Z_OK && ret != Z_STREAM_END && ret != Z_BUF_ERROR)
    return std::string("the gzip ") + unit + " does not decompress (zlib error " + std::to_string(ret) + ")";
  if (ret != Z_STREAM_END || out.size() != size)
    return sizeMismatch("gzip", unit, out.size(), size, ret == Z_STREAM_END);
  return {};
}

std::string snappy(std::span<const std::uint8_t> in, std::uint64_t size, std::vector<std::uint8_t>& out,
                   const char* unit) {
  const char* src = reinterpret_cast<const char*>(in.data());
  std::size_t claimed = 0;
  if (snappy_uncompressed_length(src, in.size(), &claimed) != SNAPPY_OK)
    return std::string("the snappy ") + unit + " does not decompress (no length at its start)";
  if (claimed != size) return sizeMismatch("snappy", unit, claimed, size, true);
  // Snappy has no streaming: the data is checked whole before the declared size is allocated.
  if (snappy_validate_compressed_buffer(src, in.size()) != SNAPPY_OK)
    return std::string("the snappy ") + unit + " does not decompress (damaged)";
  out.resize(static_cast<std::size_t>(size));
  char empty[1];
  std::size_t made = out.size();
  if (snappy_uncompress(src, in.size(), out.empty() ? empty : reinterpret_cast<char*>(out.data()), &made) !=
          SNAPPY_OK ||
      made != size)
    return std::string("the snappy ") + unit + " does not decompress (damaged)";
  return {};
}
}  // namespace

std::string decompress(const std::string& compression, std::span<const std::uint8_t> in, std::uint64_t size,
                       std::vector<std::uint8_t>& out, const char* unit) {
  out.clear();
  if (compression == "zstd") return zstd(in, size, out, unit);
  if (compression == "lz4") return lz4(in, size, out, unit);
  if (compression == "bz2") return bz2(in, size, out, unit);
  if (compression == "gzip") return gzip(in, size, out, unit);
  if (compression == "snappy") return snappy(in, size, out, unit);
  return "unknown compression";
}

}  // namespace kccd::logs::detail
