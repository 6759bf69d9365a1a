// What MCAP's reader and writer share (internal; https://mcap.dev/spec, version 0): the magic at
// both ends of a file, the records' opcodes, and the CRC-32 (zlib's) of the data section, the
// summary section and chunks.
#pragma once

#include <zlib.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>

namespace kccd::logs::detail::mcap {

/// The 8 bytes a file starts and ends with.
inline constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

/// A record's opcode, its first byte.
enum Op : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

/// `crc` (0 to start) continued over the `n` bytes at `p`.
inline std::uint32_t crc32Of(std::uint32_t crc, const std::uint8_t* p, std::size_t n) {
  while (n > 0) {  // zlib takes 32-bit lengths
    const std::size_t step = std::min<std::size_t>(n, 1u << 30);
    crc = static_cast<std::uint32_t>(crc32(crc, p, static_cast<uInt>(step)));
    p += step, n -= step;
  }
  return crc;
}

}  // namespace kccd::logs::detail::mcap
