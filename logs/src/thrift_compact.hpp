// The Thrift compact protocol (internal), as Parquet's footer and page headers use it: varints,
// zigzag integers, strings, lists and nested structs, read from bytes at hand with every length
// checked against what is left and nesting held to a fixed depth.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace kccd::logs::detail {

/// Thrift data that does not decode: cut short, a length past the end, a field of another type
/// than its struct needs, or nesting deeper than the reader follows.
class ThriftError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The compact protocol's type codes (a struct field's or a list element's).
enum ThriftType : std::uint8_t {
  kThriftStop = 0,
  kThriftTrue = 1,  // a struct field's boolean true; a list's boolean elements
  kThriftFalse = 2,
  kThriftByte = 3,
  kThriftI16 = 4,
  kThriftI32 = 5,
  kThriftI64 = 6,
  kThriftDouble = 7,
  kThriftBinary = 8,
  kThriftList = 9,
  kThriftSet = 10,
  kThriftMap = 11,
  kThriftStruct = 12,
};

/// One field of a struct: its id and type code.
struct ThriftField {
  std::int16_t id = 0;
  std::uint8_t type = kThriftStop;
};

/// A list's (or set's) element type code and element count.
struct ThriftList {
  std::uint8_t type = kThriftStop;
  std::size_t size = 0;
};

/// Reads compact-protocol values in order from `bytes` (which must outlive it). Throws ThriftError.
class CompactReader {
 public:
  /// Structs, lists and maps nest at most this deep (Parquet's own go about 6 deep).
  static constexpr std::size_t kMaxDepth = 32;

  explicit CompactReader(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}

  /// Enters a struct: its fields follow, read with nextField until it returns false.
  void beginStruct();
  /// The next field of the struct entered last; false at its end, where the struct is left.
  bool nextField(ThriftField& field);
  /// A field's integer (byte, i16, i32 or i64).
  std::int64_t integer(const ThriftField& field);
  /// A field's boolean (its value is in its type code).
  bool boolean(const ThriftField& field) const;
  /// A field's string or binary value.
  std::string binary(const ThriftField& field);
  /// A list or set field's header: its elements follow, read with the *Element functions.
  ThriftList list(const ThriftField& field);
  /// One integer element of a list of `type`.
  std::int64_t integerElement(std::uint8_t type);
  /// One string element of a list of binaries.
  std::string binaryElement();
  /// Skips one value of `type`, nested values and all.
  void skip(std::uint8_t type);
  /// Bytes read so far.
  std::size_t position() const { return pos_; }

 private:
  std::uint8_t byte();
  std::uint64_t varint();
  std::int64_t zigzag() {
    const std::uint64_t v = varint();
    return static_cast<std::int64_t>(v >> 1) ^ -static_cast<std::int64_t>(v & 1);
  }
  void enter();
  void leave() { --depth_; }

  std::span<const std::uint8_t> bytes_;
  std::size_t pos_ = 0;
  std::size_t depth_ = 0;
  std::vector<std::int16_t> last_ids_;  // per open struct: the id of its field read last
};

/// The name of a compact type code, as messages show it.
const char* thriftTypeName(std::uint8_t type);

/// Reads one struct from `r`, handing each field to `on_field`, which must read or skip its value.
template <class OnField>
void readStruct(CompactReader& r, OnField&& on_field) {
  r.beginStruct();
  ThriftField f;
  while (r.nextField(f)) on_field(f);
}

}  // namespace kccd::logs::detail
