#include "thrift_compact.hpp"

namespace kccd::logs::detail {

const char* thriftTypeName(std::uint8_t type) {
  static const char* names[] = {"stop",   "boolean", "boolean", "byte", "i16", "i32",   "i64",
                                "double", "binary",  "list",    "set",  "map", "struct"};
  return type < 13 ? names[type] : "unknown type";
}

std::uint8_t CompactReader::byte() {
  if (pos_ >= bytes_.size()) throw ThriftError("the data ends at byte " + std::to_string(pos_) + ", inside a value");
  return bytes_[pos_++];
}

std::uint64_t CompactReader::varint() {
  std::uint64_t v = 0;
  for (int shift = 0; shift < 64; shift += 7) {
    const std::uint8_t b = byte();
    v |= static_cast<std::uint64_t>(b & 0x7f) << shift;
    if ((b & 0x80) == 0) return v;
  }
  throw ThriftError("a varint at byte " + std::to_string(pos_) + " runs past 10 bytes");
}

void CompactReader::enter() {
  if (++depth_ > kMaxDepth) throw ThriftError("values nest more than " + std::to_string(kMaxDepth) + " deep");
}

void CompactReader::beginStruct() {
  enter();
  last_ids_.push_back(0);
}

bool CompactReader::nextField(ThriftField& field) {
  const std::uint8_t head = byte();
  if (head == kThriftStop) {
    last_ids_.pop_back();
    leave();
    return false;
  }
  field.type = head & 0x0f;
  const std::uint8_t delta = head >> 4;
  // A delta of 0 means the id follows in full; otherwise it counts from the previous field's id.
  const std::int64_t id = delta != 0 ? last_ids_.back() + delta : zigzag();
  if (id < -32768 || id > 32767) throw ThriftError("a field id out of range (" + std::to_string(id) + ")");
  field.id = static_cast<std::int16_t>(id);
  last_ids_.back() = field.id;
  if (field.type > kThriftStruct)
    throw ThriftError("field " + std::to_string(field.id) + " has the unknown type code " + std::to_string(field.type));
  return true;
}

std::int64_t CompactReader::integer(const ThriftField& field) {
  if (field.type < kThriftByte || field.type > kThriftI64)
    throw ThriftError("field " + std::to_string(field.id) + " is a " + thriftTypeName(field.type) + ", not an integer");
  return integerElement(field.type);
}

std::int64_t CompactReader::integerElement(std::uint8_t type) {
  if (type == kThriftByte) return static_cast<std::int8_t>(byte());
  if (type >= kThriftI16 && type <= kThriftI64) return zigzag();
  throw ThriftError(std::string("a list of ") + thriftTypeName(type) + " where integers belong");
}

bool CompactReader::boolean(const ThriftField& field) const {
  if (field.type != kThriftTrue && field.type != kThriftFalse)
    throw ThriftError("field " + std::to_string(field.id) + " is a " + thriftTypeName(field.type) + ", not a boolean");
  return field.type == kThriftTrue;
}

std::string CompactReader::binary(const ThriftField& field) {
  if (field.type != kThriftBinary)
    throw ThriftError("field " + std::to_string(field.id) + " is a " + thriftTypeName(field.type) + ", not a string");
  return binaryElement();
}

std::string CompactReader::binaryElement() {
  const std::uint64_t n = varint();
  if (n > bytes_.size() - pos_)
    throw ThriftError("a string of " + std::to_string(n) + " bytes at byte " + std::to_string(pos_) +
                      " runs past the end (" + std::to_string(bytes_.size()) + " bytes)");
  std::string s(reinterpret_cast<const char*>(bytes_.data() + pos_), static_cast<std::size_t>(n));
  pos_ += static_cast<std::size_t>(n);
  return s;
}

ThriftList CompactReader::list(const ThriftField& field) {
  if (field.type != kThriftList && field.type != kThriftSet)
    throw ThriftError("field " + std::to_string(field.id) + " is a " + thriftTypeName(field.type) + ", not a list");
  const std::uint8_t head = byte();
  ThriftList l;
  l.type = head & 0x0f;
  const std::uint64_t size = (head >> 4) == 15 ? varint() : (head >> 4);
  // Every element takes a byte at least: a longer list cannot be in the data.
  if (size > bytes_.size() - pos_)
    throw ThriftError("a list of " + std::to_string(size) + " elements at byte " + std::to_string(pos_) +
                      " runs past the end (" + std::to_string(bytes_.size()) + " bytes)");
  if (l.type == kThriftStop || l.type > kThriftStruct)
    throw ThriftError("a list of the unknown type code " + std::to_string(l.type));
  l.size = static_cast<std::size_t>(size);
  return l;
}

void CompactReader::skip(std::uint8_t type) {
  switch (type) {
    case kThriftTrue:
    case kThriftFalse:
      return;  // a struct field's boolean is in its type code (a list's is read as a byte below)
    case kThriftByte:
      byte();
      return;
    case kThriftI16:
    case kThriftI32:
    case kThriftI64:
      varint();
      return;
    case kThriftDouble:
      for (int i = 0; i < 8; ++i) byte();
      return;
    case kThriftBinary: {
      const std::uint64_t n = varint();
      if (n > bytes_.size() - pos_) throw ThriftError("a string runs past the end");
      pos_ += static_cast<std::size_t>(n);
      return;
    }
    case kThriftList:
    case kThriftSet: {
      const ThriftList l = list(ThriftField{0, type});
      enter();
      for (std::size_t i = 0; i < l.size; ++i) {
        if (l.type == kThriftTrue || l.type == kThriftFalse)
          byte();
        else
          skip(l.type);
      }
      leave();
      return;
    }
    case kThriftMap: {
      const std::uint64_t n = varint();
      if (n == 0) return;
      const std::uint8_t kinds = byte();
      if (n > bytes_.size() - pos_) throw ThriftError("a map runs past the end");
      enter();
      for (std::uint64_t i = 0; i < n; ++i) {
        for (const std::uint8_t t : {static_cast<std::uint8_t>(kinds >> 4), static_cast<std::uint8_t>(kinds & 0x0f)}) {
          if (t == kThriftTrue || t == kThriftFalse)
            byte();
          else if (t == kThriftStop || t > kThriftStruct)
            throw ThriftError("a map of the unknown type code " + std::to_string(t));
          else
            skip(t);
        }
      }
      leave();
      return;
    }
    case kThriftStruct: {
      beginStruct();
      ThriftField f;
      while (nextField(f)) skip(f.type);
      return;
    }
    default:
      throw ThriftError("a value of the unknown type code " + std::to_string(type));
  }
}

}  // namespace kccd::logs::detail
