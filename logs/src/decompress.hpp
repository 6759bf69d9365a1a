// Decompressing a chunk of a log (internal): zstd, LZ4 frames and bzip2 into a buffer that grows
// with what the data really holds, never past the size the log declares for it.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace kccd::logs::detail {

/// Decompresses `in` (`compression`: "zstd", "lz4" (frame format) or "bz2") into `out`, which must
/// end up exactly `size` bytes. Returns "" or the problem ("does not decompress: ...", "decompresses
/// to N bytes, not the M it declares").
std::string decompress(const std::string& compression, std::span<const std::uint8_t> in, std::uint64_t size,
                       std::vector<std::uint8_t>& out);

}  // namespace kccd::logs::detail
