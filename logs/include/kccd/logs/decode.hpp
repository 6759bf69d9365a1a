// Decoding one message's bytes with its definition: ROS 2's CDR (the 4-byte encapsulation header,
// either byte order, each primitive aligned to its size) and ROS 1's serialization (little-endian,
// packed). No count or length is trusted beyond the bytes that remain.
#pragma once

#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>

#include "kccd/logs/message_definition.hpp"
#include "kccd/logs/message_value.hpp"

namespace kccd::logs {

/// Bytes that do not decode as the definition says: the problem and the byte offset in the message.
class DecodeError : public std::runtime_error {
 public:
  DecodeError(std::size_t offset, const std::string& problem) : std::runtime_error(problem), offset_(offset) {}
  std::size_t offset() const { return offset_; }

 private:
  std::size_t offset_;
};

/// Decodes CDR-encoded `data` (encapsulation header first) as the root type of `types`.
/// Throws DecodeError. The result's byte views point into `data`.
Value decodeCdr(const MessageDefinitions& types, std::span<const std::uint8_t> data);
/// Decodes ROS 1 serialized `data` as the root type of `types`. Throws DecodeError.
Value decodeRos1(const MessageDefinitions& types, std::span<const std::uint8_t> data);

}  // namespace kccd::logs
