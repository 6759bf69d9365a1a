// ROS message definitions (the .msg text a bag stores beside its messages: MCAP's "ros2msg" and
// "ros1msg" schemas, a ROS 1 connection's message_definition) parsed into field layouts, so a
// message is decoded from what the bag says it is, not from what a reader assumes.
#pragma once

#include <cstddef>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace kccd::logs {

/// The built-in field types (ROS 1's time and duration are two 32-bit fields, seconds first).
enum class Primitive {
  None,
  Bool,
  Byte,
  Char,
  Int8,
  UInt8,
  Int16,
  UInt16,
  Int32,
  UInt32,
  Int64,
  UInt64,
  Float32,
  Float64,
  String,
  WString,
  Time,
  Duration
};

/// One field: its type (a primitive, or another message by full name), array shape and name.
struct Field {
  std::string name;
  Primitive primitive = Primitive::None;  ///< None: a message type, `type_name`
  std::string type_name;                  ///< "pkg/Type" for a message type
  enum class Array { None, Fixed, Dynamic } array = Array::None;
  std::size_t length = 0;  ///< a fixed array's length
};

/// A message type: its full name ("pkg/Type") and fields in order.
struct MessageType {
  std::string name;
  std::vector<Field> fields;
};

/// Which syntax and type rules a definition follows.
enum class Dialect { Ros1, Ros2 };

/// A definition that cannot be read: the problem and its 1-based line in the definition text.
class DefinitionError : public std::runtime_error {
 public:
  DefinitionError(std::size_t line, const std::string& problem) : std::runtime_error(problem), line_(line) {}
  std::size_t line() const { return line_; }

 private:
  std::size_t line_;
};

/// A root type and every type it uses, by full name ("pkg/Type"; "pkg/msg/Type" is stored so too).
class MessageDefinitions {
 public:
  /// Parses `text`: the root type's definition, then each dependency after a line of '=' and a
  /// "MSG: pkg/Type" line. Throws DefinitionError for bad syntax or a type used but not defined.
  static MessageDefinitions parse(std::string_view root_name, std::string_view text, Dialect dialect);

  const MessageType& root() const { return types_.at(root_); }
  /// The type of that full name, or null.
  const MessageType* find(const std::string& name) const;
  Dialect dialect() const { return dialect_; }

 private:
  std::string root_;
  std::map<std::string, MessageType> types_;
  Dialect dialect_ = Dialect::Ros2;
};

/// "pkg/msg/Type" -> "pkg/Type" (ROS 2 names carry the interface kind; ROS 1 names do not).
std::string normalTypeName(std::string_view name);

}  // namespace kccd::logs
