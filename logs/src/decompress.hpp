// Decompressing a chunk of a log or a page of a Parquet file (internal): zstd, LZ4 frames, bzip2,
// gzip (or zlib) and snappy into a buffer that grows with what the data really holds, never past
// the size the file declares for it.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace kccd::logs::detail {

/// Decompresses `in` (`compression`: "zstd", "lz4" (frame format), "bz2", "gzip" (gzip or zlib
/// streams, members one after another) or "snappy" (raw, unframed)) into `out`, which must end up
/// exactly `size` bytes. Returns "" or the problem, naming the data as `unit` ("the zstd chunk
/// does not decompress: ...", "the snappy page decompresses to N bytes, not the M it declares").
std::string decompress(const std::string& compression, std::span<const std::uint8_t> in, std::uint64_t size,
                       std::vector<std::uint8_t>& out, const char* unit = "chunk");

/// The bytes a log's chunks may decompress to in all: 256 MiB plus 256 times the file's size. Far
/// above what real logs compress by (images hardly compress, joint states some tens of times),
/// it keeps a crafted file (hundreds of tiny chunks that each declare 64 MiB of zeros: 30 GiB in
/// 1 MiB) from running for minutes.
inline std::uint64_t decompressBudget(std::uint64_t file_bytes) {
  return (std::uint64_t{256} << 20) + 256 * std::min<std::uint64_t>(file_bytes, std::uint64_t{1} << 50);
}

/// Takes `bytes` from what is `left` of the budget; "" or the problem when it would run out.
inline std::string takeFromBudget(std::uint64_t& left, std::uint64_t bytes) {
  if (bytes > left)
    return "the chunks decompress to more than 256 MiB plus 256 times the file's size in all (a decompression bomb)";
  left -= bytes;
  return {};
}

}  // namespace kccd::logs::detail
