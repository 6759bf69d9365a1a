// libFuzzer target: ROS message definitions and messages decoded with them (kccd::logs: the
// definition parser, CDR in both byte orders and ROS 1's serialization). The input is a dialect
// byte, a 16-bit definition length, the definition text and the message bytes. A definition must
// parse or throw DefinitionError; a message must decode or throw DecodeError at an offset inside
// it; anything else is a finding.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <optional>
#include <span>
#include <string_view>

#include "kccd/logs/decode.hpp"
#include "kccd/logs/message_definition.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace kccd::logs;
  if (size < 3) return 0;
  const Dialect dialect = (data[0] & 1) ? Dialect::Ros1 : Dialect::Ros2;
  const std::size_t n =
      std::min<std::size_t>(size - 3, static_cast<std::size_t>(data[1]) | (static_cast<std::size_t>(data[2]) << 8));
  const std::string_view text(reinterpret_cast<const char*>(data + 3), n);
  const std::span<const std::uint8_t> message(data + 3 + n, size - 3 - n);
  std::optional<MessageDefinitions> types;
  try {
    types = MessageDefinitions::parse("fuzz_msgs/Root", text, dialect);
  } catch (const DefinitionError&) {
    return 0;
  }
  for (const bool cdr : {true, false}) {
    try {
      const Value v = cdr ? decodeCdr(*types, message) : decodeRos1(*types, message);
      if (v.kind != Value::Kind::Struct || v.items.size() != types->root().fields.size()) std::abort();
    } catch (const DecodeError& e) {
      if (e.offset() > message.size()) std::abort();
    }
  }
  return 0;
}
