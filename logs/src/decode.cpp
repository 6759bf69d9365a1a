#include "kccd/logs/decode.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>

namespace kccd::logs {

const Value* Value::field(std::string_view name) const {
  if (kind != Kind::Struct || type == nullptr) return nullptr;
  for (std::size_t i = 0; i < type->fields.size() && i < items.size(); ++i)
    if (type->fields[i].name == name) return &items[i];
  return nullptr;
}

double Value::number() const {
  switch (kind) {
    case Kind::Bool:
    case Kind::UInt:
      return static_cast<double>(u);
    case Kind::Int:
      return static_cast<double>(i);
    case Kind::Float:
      return f;
    default:
      return std::numeric_limits<double>::quiet_NaN();
  }
}

namespace {

// A whole number of a header field, when it is one that fits (a definition may declare any type).
std::optional<std::int64_t> wholeField(const Value& v) {
  constexpr std::int64_t kLimit = std::int64_t{1} << 33;
  if (v.kind == Value::Kind::Int && v.i > -kLimit && v.i < kLimit) return v.i;
  if (v.kind == Value::Kind::UInt && v.u < static_cast<std::uint64_t>(kLimit)) return static_cast<std::int64_t>(v.u);
  return std::nullopt;
}

}  // namespace

std::optional<std::int64_t> headerStamp(const Value& message) {
  const Value* header = message.field("header");
  if (!header) return std::nullopt;
  const Value* stamp = header->field("stamp");
  if (!stamp) return std::nullopt;
  const Value* sec = nullptr;
  const Value* nsec = nullptr;
  if (stamp->kind == Value::Kind::Array && stamp->items.size() == 2)
    sec = &stamp->items[0], nsec = &stamp->items[1];  // ROS 1 time
  else
    sec = stamp->field("sec"), nsec = stamp->field("nanosec");
  if (!sec || !nsec) return std::nullopt;
  const auto s = wholeField(*sec), n = wholeField(*nsec);
  if (!s || !n) return std::nullopt;
  return *s * 1000000000 + *n;
}

namespace {

// The wire rules: CDR aligns each primitive to its size (from the byte after the encapsulation
// header) and may be big-endian; ROS 1 is packed little-endian, and its strings carry no NUL.
class Decoder {
 public:
  Decoder(const MessageDefinitions& types, std::span<const std::uint8_t> data, std::size_t origin, bool cdr, bool big)
      : types_(types), data_(data), pos_(origin), origin_(origin), cdr_(cdr), big_(big) {}

  Value message(const MessageType& t, int depth) {
    if (depth > 64) throw DecodeError(pos_, "types nested more than 64 deep");
    // Fields of types that take no bytes are not counted against the data: the values made are
    // (a message type whose fields are two of a type of two of a type ... of an empty type holds
    // 2^64 values in no bytes at all).
    if (++values_ > 4 * data_.size() + 4096)
      throw DecodeError(pos_, "more than " + std::to_string(4 * data_.size() + 4096) + " nested messages for " +
                                  std::to_string(data_.size()) + " bytes (types that take no bytes, multiplied)");
    Value v;
    v.kind = Value::Kind::Struct;
    v.type = &t;
    v.items.reserve(t.fields.size());
    for (const Field& f : t.fields) v.items.push_back(field(f, depth));
    return v;
  }

  std::size_t position() const { return pos_; }

 private:
  [[noreturn]] void fail(const std::string& what) const { throw DecodeError(pos_, what); }

  void align(std::size_t n) {
    if (!cdr_) return;
    const std::size_t rel = pos_ - origin_;
    const std::size_t pad = (n - rel % n) % n;
    need(pad, "padding");
    pos_ += pad;
  }
  // `what`, and `name` after it when given, says what was being read (the text is made on failure only).
  void need(std::size_t n, const char* what, const std::string* name = nullptr) const {
    if (n > data_.size() - pos_)
      fail(std::string("the message ends inside ") + what + (name ? " " + *name : std::string()) + " (" +
           std::to_string(n) + " bytes needed, " + std::to_string(data_.size() - pos_) + " left)");
  }
  template <class T>
  T read(const char* what, const std::string* name = nullptr) {
    align(sizeof(T));
    need(sizeof(T), what, name);
    std::uint8_t b[sizeof(T)];
    std::memcpy(b, data_.data() + pos_, sizeof(T));
    if (big_)
      for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    pos_ += sizeof(T);
    T v;
    std::memcpy(&v, b, sizeof(T));
    return v;
  }
  // A 32-bit count of `what` ("a string", or "the array" followed by `name`), believed only as far
  // as the remaining bytes can hold it. The message text is made only when it is needed.
  std::uint32_t count(std::size_t least_element_bytes, const char* what, const std::string* name = nullptr,
                      const char* unit = "elements") {
    const std::uint32_t n = read<std::uint32_t>(what, name);
    if (least_element_bytes > 0 && n > (data_.size() - pos_) / least_element_bytes)
      fail(std::string(what) + (name ? " " + *name : std::string()) + " of " + std::to_string(n) + " " + unit +
           ", more than the " + std::to_string(data_.size() - pos_) + " bytes left hold");
    return n;
  }
  static std::size_t sizeOf(Primitive p) {
    switch (p) {
      case Primitive::Bool:
      case Primitive::Byte:
      case Primitive::Char:
      case Primitive::Int8:
      case Primitive::UInt8:
        return 1;
      case Primitive::Int16:
      case Primitive::UInt16:
        return 2;
      case Primitive::Int32:
      case Primitive::UInt32:
      case Primitive::Float32:
        return 4;
      case Primitive::Int64:
      case Primitive::UInt64:
      case Primitive::Float64:
      case Primitive::Time:
      case Primitive::Duration:
        return 8;
      default:
        return 4;  // strings: at least their length
    }
  }

  Value primitive(Primitive p) {
    Value v;
    switch (p) {
      case Primitive::Bool:
        v.kind = Value::Kind::Bool, v.u = read<std::uint8_t>("a bool") != 0;
        break;
      case Primitive::Byte:
      case Primitive::Char:
      case Primitive::UInt8:
        v.kind = Value::Kind::UInt, v.u = read<std::uint8_t>("a uint8");
        break;
      case Primitive::Int8:
        v.kind = Value::Kind::Int, v.i = read<std::int8_t>("an int8");
        break;
      case Primitive::UInt16:
        v.kind = Value::Kind::UInt, v.u = read<std::uint16_t>("a uint16");
        break;
      case Primitive::Int16:
        v.kind = Value::Kind::Int, v.i = read<std::int16_t>("an int16");
        break;
      case Primitive::UInt32:
        v.kind = Value::Kind::UInt, v.u = read<std::uint32_t>("a uint32");
        break;
      case Primitive::Int32:
        v.kind = Value::Kind::Int, v.i = read<std::int32_t>("an int32");
        break;
      case Primitive::UInt64:
        v.kind = Value::Kind::UInt, v.u = read<std::uint64_t>("a uint64");
        break;
      case Primitive::Int64:
        v.kind = Value::Kind::Int, v.i = read<std::int64_t>("an int64");
        break;
      case Primitive::Float32:
        v.kind = Value::Kind::Float, v.f = read<float>("a float32");
        break;
      case Primitive::Float64:
        v.kind = Value::Kind::Float, v.f = read<double>("a float64");
        break;
      case Primitive::Time:
      case Primitive::Duration: {  // ROS 1: seconds and nanoseconds, as a structure-less pair
        v.kind = Value::Kind::Array;
        Value s, ns;
        if (p == Primitive::Time) {
          s.kind = ns.kind = Value::Kind::UInt;
          s.u = read<std::uint32_t>("a time"), ns.u = read<std::uint32_t>("a time");
        } else {
          s.kind = ns.kind = Value::Kind::Int;
          s.i = read<std::int32_t>("a duration"), ns.i = read<std::int32_t>("a duration");
        }
        v.items = {s, ns};
        break;
      }
      case Primitive::String: {
        v.kind = Value::Kind::String;
        const std::uint32_t n = count(1, "a string", nullptr, "bytes");
        if (cdr_ && n > 0) {  // CDR counts the terminating NUL
          v.s.assign(reinterpret_cast<const char*>(data_.data() + pos_), n - 1);
          if (data_[pos_ + n - 1] != 0) fail("a string without its terminating NUL");
        } else {
          v.s.assign(reinterpret_cast<const char*>(data_.data() + pos_), n);
        }
        pos_ += n;
        break;
      }
      case Primitive::WString:
        fail("wstring fields are not read");
      case Primitive::None:
        fail("internal: not a primitive");
    }
    return v;
  }

  bool isByte(Primitive p) const { return p == Primitive::UInt8 || p == Primitive::Byte || p == Primitive::Char; }

  Value field(const Field& f, int depth) {
    const MessageType* sub = nullptr;
    if (f.primitive == Primitive::None) {
      sub = types_.find(f.type_name);
      if (!sub) fail("the type " + f.type_name + " is not defined");
    }
    if (f.array == Field::Array::None) return sub ? message(*sub, depth + 1) : primitive(f.primitive);
    std::size_t n = f.length;
    if (f.array == Field::Array::Dynamic)
      n = count(sub ? 0 : sizeOf(f.primitive), "the array", &f.name);
    else if (!sub && n > (data_.size() - pos_) / sizeOf(f.primitive))
      fail("the array " + f.name + " of " + std::to_string(n) + " elements, more than the bytes left hold");
    Value v;
    if (!sub && isByte(f.primitive)) {  // bytes: a view, not n values
      v.kind = Value::Kind::Bytes;
      need(n, "a byte array");
      v.bytes = data_.subspan(pos_, n);
      pos_ += n;
      return v;
    }
    v.kind = Value::Kind::Array;
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t before = pos_;
      v.items.push_back(sub ? message(*sub, depth + 1) : primitive(f.primitive));
      // An element that takes no bytes (an empty message type) cannot be counted against the data.
      if (pos_ == before && n > data_.size())
        fail("the array " + f.name + " of " + std::to_string(n) + " empty elements");
    }
    return v;
  }

  const MessageDefinitions& types_;
  std::span<const std::uint8_t> data_;
  std::size_t pos_, origin_;
  bool cdr_, big_;
  std::size_t values_ = 0;  // messages decoded so far
};

}  // namespace

Value decodeCdr(const MessageDefinitions& types, std::span<const std::uint8_t> data) {
  if (data.size() < 4) throw DecodeError(0, "shorter than CDR's 4-byte encapsulation header");
  // Plain CDR only (what ROS 2's middlewares write): 0x0000 big-endian, 0x0001 little-endian.
  if (data[0] != 0 || data[1] > 1)
    throw DecodeError(0, "CDR encapsulation 0x" + std::string(1, "0123456789abcdef"[data[0] >> 4]) +
                             "0123456789abcdef"[data[0] & 15] + "0123456789abcdef"[data[1] >> 4] +
                             "0123456789abcdef"[data[1] & 15] + " is not plain CDR (0x0000 or 0x0001)");
  Decoder d(types, data, 4, true, data[1] == 0);
  return d.message(types.root(), 0);
}

Value decodeRos1(const MessageDefinitions& types, std::span<const std::uint8_t> data) {
  Decoder d(types, data, 0, false, false);
  return d.message(types.root(), 0);
}

}  // namespace kccd::logs
