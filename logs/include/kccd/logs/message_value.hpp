// A decoded message as a tree of values: numbers, strings, byte arrays (views into the message,
// not copies: an image's pixels are not copied), arrays and structures with their field names.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "kccd/logs/message_definition.hpp"

namespace kccd::logs {

/// One value of a decoded message.
struct Value {
  enum class Kind { Bool, Int, UInt, Float, String, Bytes, Array, Struct };
  Kind kind = Kind::Struct;
  std::int64_t i = 0;
  std::uint64_t u = 0;
  double f = 0.0;
  std::string s;
  std::span<const std::uint8_t> bytes;  ///< uint8/byte/char arrays: a view into the message's data
  std::vector<Value> items;             ///< an array's elements, a structure's fields in order
  const MessageType* type = nullptr;    ///< a structure's type (its field names)

  /// A structure's field of that name, or null.
  const Value* field(std::string_view name) const;
  /// A number of any kind as a double (booleans as 0 and 1); NaN for anything else.
  double number() const;
};

/// A message's header stamp in nanoseconds: the root's `header.stamp`, ROS 2's {sec, nanosec} or
/// ROS 1's time. None without one, or when its fields are not whole numbers within ±2^33 (a
/// definition may declare any type); 0 is a stamp the publisher left unset.
std::optional<std::int64_t> headerStamp(const Value& message);

}  // namespace kccd::logs
