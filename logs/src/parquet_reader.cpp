#include "kccd/logs/parquet_reader.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <span>

#include "decompress.hpp"
#include "kccd/input_error.hpp"
#include "thrift_compact.hpp"

namespace kccd::logs {
// Internal: in a namespace of its own, as the library compiles its files joined (unity builds).
namespace detail::parquet {

using detail::CompactReader;
using detail::readStruct;
using detail::ThriftError;
using detail::ThriftField;
using detail::ThriftList;

// Parquet's enumerations (parquet.thrift), the values this reader tells apart.
enum Physical : int { kBoolean, kInt32, kInt64, kInt96, kFloat, kDouble, kByteArray, kFixedLenByteArray };
enum Repetition : int { kRequired, kOptional, kRepeated };
enum Codec : int { kUncompressed, kSnappy, kGzip, kLzo, kBrotli, kLz4, kZstd, kLz4Raw };
enum Encoding : int { kPlain = 0, kPlainDictionary = 2, kRle = 3, kBitPacked = 4, kRleDictionary = 8 };
enum PageType : int { kDataPage, kIndexPage, kDictionaryPage, kDataPageV2 };
enum Converted : int { kConvertedList = 3, kConvertedDecimal = 5, kConvertedUint8 = 11, kConvertedUint64 = 14 };

constexpr std::uint8_t kMagic[4] = {'P', 'A', 'R', '1'};
constexpr std::uint8_t kEncryptedMagic[4] = {'P', 'A', 'R', 'E'};
// Schemas nest at most this deep (a dataset's go 4 or 5 deep; recursion stays shallow).
constexpr int kMaxSchemaDepth = 64;
// What each value a page holds costs the read's budget besides its bytes: its place in the result
// (a double and a row offset), so that run-length data cannot expand without limit.
constexpr std::uint64_t kValueCost = sizeof(double) + sizeof(std::size_t);

const char* physicalName(int type) {
  static const char* names[] = {"BOOLEAN", "INT32",  "INT64",      "INT96",
                                "FLOAT",   "DOUBLE", "BYTE_ARRAY", "FIXED_LEN_BYTE_ARRAY"};
  return type >= 0 && type < 8 ? names[type] : "an unknown type";
}

std::string codecName(int codec) {
  static const char* names[] = {"UNCOMPRESSED", "SNAPPY", "GZIP", "LZO", "BROTLI", "LZ4", "ZSTD", "LZ4_RAW"};
  return codec >= 0 && codec < 8 ? names[codec] : "codec " + std::to_string(codec);
}

std::string encodingName(int encoding) {
  static const char* names[] = {"PLAIN",          "GROUP_VAR_INT",       "PLAIN_DICTIONARY",        "RLE",
                                "BIT_PACKED",     "DELTA_BINARY_PACKED", "DELTA_LENGTH_BYTE_ARRAY", "DELTA_BYTE_ARRAY",
                                "RLE_DICTIONARY", "BYTE_STREAM_SPLIT"};
  return encoding >= 0 && encoding < 10 ? names[encoding] : "encoding " + std::to_string(encoding);
}

std::uint32_t le32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}
std::uint64_t le64(const std::uint8_t* p) { return le32(p) | static_cast<std::uint64_t>(le32(p + 4)) << 32; }

// ---- the footer's structures, the fields this reader uses

struct SchemaElement {
  std::string name;
  int type = -1;  // physical type; -1 for a group
  std::int64_t typeLength = 0;
  int repetition = kRequired;
  std::int64_t numChildren = -1;  // -1: a leaf
  int converted = -1;
  std::int64_t scale = 0;
  bool list = false;  // LIST by its logical type
  bool isUnsigned = false, decimal = false;
};

struct Statistics {
  std::optional<std::string> min, max;            // deprecated: signed order (right for signed integers only)
  std::optional<std::string> minValue, maxValue;  // in the column's own order
};

struct ChunkMeta {
  bool hasMeta = false, encrypted = false, external = false;
  int type = -1, codec = kUncompressed;
  std::int64_t numValues = 0, totalCompressed = 0, dataPageOffset = -1, dictionaryPageOffset = -1;
  Statistics stats;
};

struct GroupMeta {
  std::int64_t rows = -1;
  std::vector<ChunkMeta> chunks;
};

struct FileMeta {
  std::vector<SchemaElement> schema;
  std::int64_t rows = -1;
  std::vector<GroupMeta> groups;
  std::vector<std::pair<std::string, std::string>> keyValues;
  bool encrypted = false;
};

std::int32_t int32Of(CompactReader& r, const ThriftField& f) {
  const std::int64_t v = r.integer(f);
  if (v < std::numeric_limits<std::int32_t>::min() || v > std::numeric_limits<std::int32_t>::max())
    throw ThriftError("field " + std::to_string(f.id) + " holds " + std::to_string(v) + ", out of a 32-bit range");
  return static_cast<std::int32_t>(v);
}

void needStruct(const ThriftField& f) {
  if (f.type != detail::kThriftStruct)
    throw ThriftError("field " + std::to_string(f.id) + " is a " + detail::thriftTypeName(f.type) + ", not a struct");
}

// Calls `each` once per element of the list of structs `f`, each element's struct to be read by it.
template <class Each>
void forEachStruct(CompactReader& r, const ThriftField& f, Each&& each) {
  const ThriftList l = r.list(f);
  if (l.type != detail::kThriftStruct)
    throw ThriftError("field " + std::to_string(f.id) + " is a list of " + detail::thriftTypeName(l.type) +
                      ", not of structs");
  for (std::size_t i = 0; i < l.size; ++i) each();
}

void readLogicalType(CompactReader& r, const ThriftField& field, SchemaElement& e) {
  needStruct(field);
  readStruct(r, [&](const ThriftField& f) {
    if (f.id == 3) {
      e.list = true;
      r.skip(f.type);
    } else if (f.id == 5) {
      e.decimal = true;
      needStruct(f);
      readStruct(r, [&](const ThriftField& d) { d.id == 1 ? void(e.scale = int32Of(r, d)) : r.skip(d.type); });
    } else if (f.id == 10) {
      needStruct(f);
      readStruct(r, [&](const ThriftField& i) { i.id == 2 ? void(e.isUnsigned = !r.boolean(i)) : r.skip(i.type); });
    } else {
      r.skip(f.type);
    }
  });
}

SchemaElement readSchemaElement(CompactReader& r) {
  SchemaElement e;
  readStruct(r, [&](const ThriftField& f) {
    switch (f.id) {
      case 1:
        e.type = int32Of(r, f);
        break;
      case 2:
        e.typeLength = int32Of(r, f);
        break;
      case 3:
        e.repetition = int32Of(r, f);
        break;
      case 4:
        e.name = r.binary(f);
        break;
      case 5:
        e.numChildren = int32Of(r, f);
        break;
      case 6:
        e.converted = int32Of(r, f);
        break;
      case 7:
        e.scale = int32Of(r, f);
        break;
      case 10:
        readLogicalType(r, f, e);
        break;
      default:
        r.skip(f.type);
    }
  });
  if (e.converted >= kConvertedUint8 && e.converted <= kConvertedUint64) e.isUnsigned = true;
  if (e.converted == kConvertedDecimal) e.decimal = true;
  return e;
}

Statistics readStatistics(CompactReader& r, const ThriftField& field) {
  needStruct(field);
  Statistics s;
  readStruct(r, [&](const ThriftField& f) {
    switch (f.id) {
      case 1:
        s.max = r.binary(f);
        break;
      case 2:
        s.min = r.binary(f);
        break;
      case 5:
        s.maxValue = r.binary(f);
        break;
      case 6:
        s.minValue = r.binary(f);
        break;
      default:
        r.skip(f.type);
    }
  });
  return s;
}

void readColumnMetaData(CompactReader& r, const ThriftField& field, ChunkMeta& c) {
  needStruct(field);
  c.hasMeta = true;
  readStruct(r, [&](const ThriftField& f) {
    switch (f.id) {
      case 1:
        c.type = int32Of(r, f);
        break;
      case 4:
        c.codec = int32Of(r, f);
        break;
      case 5:
        c.numValues = r.integer(f);
        break;
      case 7:
        c.totalCompressed = r.integer(f);
        break;
      case 9:
        c.dataPageOffset = r.integer(f);
        break;
      case 11:
        c.dictionaryPageOffset = r.integer(f);
        break;
      case 12:
        c.stats = readStatistics(r, f);
        break;
      default:
        r.skip(f.type);
    }
  });
}

ChunkMeta readColumnChunk(CompactReader& r) {
  ChunkMeta c;
  readStruct(r, [&](const ThriftField& f) {
    if (f.id == 1) {
      c.external = !r.binary(f).empty();  // file_path: the chunk is in another file
    } else if (f.id == 3) {
      readColumnMetaData(r, f, c);
    } else {
      c.encrypted = c.encrypted || f.id == 8 || f.id == 9;  // crypto_metadata, encrypted_column_metadata
      r.skip(f.type);
    }
  });
  return c;
}

FileMeta readFileMetaData(CompactReader& r) {
  FileMeta m;
  readStruct(r, [&](const ThriftField& f) {
    switch (f.id) {
      case 2:
        forEachStruct(r, f, [&] { m.schema.push_back(readSchemaElement(r)); });
        break;
      case 3:
        m.rows = r.integer(f);
        break;
      case 4:
        forEachStruct(r, f, [&] {
          GroupMeta& g = m.groups.emplace_back();
          readStruct(r, [&](const ThriftField& gf) {
            if (gf.id == 1)
              forEachStruct(r, gf, [&] { g.chunks.push_back(readColumnChunk(r)); });
            else if (gf.id == 3)
              g.rows = r.integer(gf);
            else
              r.skip(gf.type);
          });
        });
        break;
      case 5:
        forEachStruct(r, f, [&] {
          std::pair<std::string, std::string> kv;
          readStruct(r, [&](const ThriftField& k) {
            k.id == 1 ? void(kv.first = r.binary(k)) : k.id == 2 ? void(kv.second = r.binary(k)) : r.skip(k.type);
          });
          m.keyValues.push_back(std::move(kv));
        });
        break;
      case 8:  // encryption_algorithm: a plaintext footer over encrypted columns
        m.encrypted = true;
        r.skip(f.type);
        break;
      default:
        r.skip(f.type);
    }
  });
  return m;
}

struct PageHeader {
  int type = -1;
  std::int64_t uncompressed = -1, compressed = -1;
  bool hasBody = false;  // the header of its type is there
  std::int64_t numValues = -1;
  int encoding = -1, defEncoding = kRle, repEncoding = kRle;  // v1 and dictionary pages
  std::int64_t defLength = 0, repLength = 0;                  // v2: the levels' bytes, before the values
  bool isCompressed = true;                                   // v2
};

// Reads a data page header (field 5 of the page header: v1), a dictionary page header (7) or a
// data page header v2 (8) into `h`.
void readPageBody(CompactReader& r, const ThriftField& field, PageHeader& h) {
  needStruct(field);
  const bool v1 = field.id == 5, v2 = field.id == 8;
  readStruct(r, [&](const ThriftField& d) {
    if (d.id == 1)
      h.numValues = int32Of(r, d);
    else if (d.id == 2 && !v2)
      h.encoding = int32Of(r, d);
    else if (d.id == 3 && v1)
      h.defEncoding = int32Of(r, d);
    else if (d.id == 4 && v1)
      h.repEncoding = int32Of(r, d);
    else if (d.id == 4 && v2)
      h.encoding = int32Of(r, d);
    else if (d.id == 5 && v2)
      h.defLength = int32Of(r, d);
    else if (d.id == 6 && v2)
      h.repLength = int32Of(r, d);
    else if (d.id == 7 && v2)
      h.isCompressed = r.boolean(d);
    else
      r.skip(d.type);
  });
}

PageHeader readPageHeader(CompactReader& r) {
  PageHeader h;
  int body = -1;  // the field id of the header read for the page's type
  readStruct(r, [&](const ThriftField& f) {
    if (f.id == 1) {
      h.type = int32Of(r, f);
    } else if (f.id == 2) {
      h.uncompressed = int32Of(r, f);
    } else if (f.id == 3) {
      h.compressed = int32Of(r, f);
    } else if (f.id == 5 || f.id == 7 || f.id == 8) {
      if (body >= 0) throw ThriftError("the page header holds headers of two page types");
      body = f.id;
      readPageBody(r, f, h);
    } else {
      r.skip(f.type);
    }
  });
  h.hasBody = (body == 5 && h.type == kDataPage) || (body == 7 && h.type == kDictionaryPage) ||
              (body == 8 && h.type == kDataPageV2);
  return h;
}

// ---- the schema's leaves

struct Leaf {
  std::string name;
  int type = -1;
  std::int64_t typeLength = 0;
  int maxDef = 0, maxRep = 0;
  int listDef = 0;  // the definition level at which the list holds an element
  bool isUnsigned = false;
  double divisor = 1;   // a decimal's 10^scale
  std::string refused;  // why this reader does not read the column (said when it is read), or ""
  bool isBytes() const { return type == kByteArray || type == kFixedLenByteArray; }
};

// Walks the schema's elements in their stored (depth-first) order into leaves, naming each by its
// fields from the root down, less a list's inner levels.
class SchemaWalk {
 public:
  SchemaWalk(const std::string& path, const std::vector<SchemaElement>& schema) : path_(path), s_(schema) {}

  std::vector<Leaf> leaves() {
    if (s_.empty()) fail("the footer has no schema");
    if (s_[0].numChildren < 0) fail("the schema's root is not a group");
    std::size_t next = 1;
    for (std::int64_t c = 0; c < s_[0].numChildren; ++c) next = walk(next, {}, 0, 0, 0, 0, 1);
    if (next != s_.size())
      fail("the schema has " + std::to_string(s_.size()) + " elements, its root's fields " + std::to_string(next));
    return std::move(leaves_);
  }

 private:
  [[noreturn]] void fail(const std::string& problem) const {
    throw InputError(InputLocation{path_, 0, 0, {}}, problem);
  }

  // Walks element `i` under `prefix` with the levels above it; `unnamed` of the levels from `i`
  // down are a list's inner ones and are left out of names. Returns the element after its subtree.
  std::size_t walk(std::size_t i, const std::string& prefix, int def, int rep, int listDef, int unnamed, int depth) {
    if (i >= s_.size()) fail("the schema ends inside a group (its elements count fewer fields than its groups hold)");
    if (depth > kMaxSchemaDepth) fail("the schema nests more than " + std::to_string(kMaxSchemaDepth) + " deep");
    const SchemaElement& e = s_[i];
    const std::string name = unnamed > 0 ? prefix : prefix.empty() ? e.name : prefix + "/" + e.name;
    if (e.repetition == kOptional || e.repetition == kRepeated) ++def;
    if (e.repetition == kRepeated) ++rep, listDef = def;
    if (e.repetition < kRequired || e.repetition > kRepeated)
      fail("field " + printable(name) + " has the unknown repetition " + std::to_string(e.repetition));
    if (e.numChildren < 0) return leaf(i, name, def, rep, listDef);
    if (e.numChildren == 0) fail("group " + printable(name) + " has no fields");
    std::size_t next = i + 1;
    if (listElement(i)) {
      // A list's repeated child is a level of its own: its one field is the element (three
      // levels), or it is the element itself (the legacy two levels).
      const SchemaElement& middle = s_[i + 1];
      const bool three = middle.numChildren == 1 && middle.name != "array" && middle.name != e.name + "_tuple";
      return walk(next, name, def, rep, listDef, three ? 2 : 1, depth + 1);
    }
    for (std::int64_t c = 0; c < e.numChildren; ++c)
      next = walk(next, name, def, rep, listDef, std::max(unnamed - 1, 0), depth + 1);
    return next;
  }

  // True when element `i` is a LIST whose one field is repeated (the form lists take).
  bool listElement(std::size_t i) const {
    const SchemaElement& e = s_[i];
    return (e.list || e.converted == kConvertedList) && e.numChildren == 1 && i + 1 < s_.size() &&
           s_[i + 1].repetition == kRepeated;
  }

  std::size_t leaf(std::size_t i, const std::string& name, int def, int rep, int listDef) {
    const SchemaElement& e = s_[i];
    const std::string column = "column " + printable(name);
    if (e.type < kBoolean || e.type > kFixedLenByteArray)
      fail(column + " has the unknown physical type " + std::to_string(e.type));
    if (e.type == kFixedLenByteArray && e.typeLength <= 0)
      fail(column + " is FIXED_LEN_BYTE_ARRAY of " + std::to_string(e.typeLength) + " bytes");
    Leaf l;
    l.name = name;
    l.type = e.type;
    l.typeLength = e.typeLength;
    l.maxDef = def;
    l.maxRep = rep;
    l.listDef = listDef;
    l.isUnsigned = e.isUnsigned;
    if (e.decimal && (e.type == kInt32 || e.type == kInt64)) l.divisor = std::pow(10.0, static_cast<double>(e.scale));
    // Refused when read, not when the file is opened: a table's other columns stay readable
    // (LeRobot v3.0's episode tables hold image statistics as lists of lists).
    if (e.type == kInt96) l.refused = column + " is INT96 (a legacy timestamp), which this reader does not read";
    if (rep > 1)
      l.refused = column + " is a list of lists (" + std::to_string(rep) +
                  " repetition levels), which this reader does not read";
    leaves_.push_back(std::move(l));
    return i + 1;
  }

  const std::string& path_;
  const std::vector<SchemaElement>& s_;
  std::vector<Leaf> leaves_;
};

// ---- the RLE / bit-packed hybrid (levels, dictionary indices, RLE booleans)

// Decodes `count` values of `width` bits (at most 32) from `data`, handing each run to
// `put(value, times)`. Returns "" or the problem.
template <class Put>
std::string decodeHybrid(std::span<const std::uint8_t> data, int width, std::size_t count, Put&& put) {
  const std::size_t value_bytes = static_cast<std::size_t>(width + 7) / 8;
  std::size_t pos = 0, done = 0;
  while (done < count) {
    std::uint64_t header = 0;
    for (int shift = 0;; shift += 7) {
      if (pos >= data.size() || shift > 35)
        return "the RLE data ends after " + std::to_string(done) + " of its " + std::to_string(count) + " values";
      header |= static_cast<std::uint64_t>(data[pos] & 0x7f) << shift;
      if ((data[pos++] & 0x80) == 0) break;
    }
    const std::size_t left = count - done;
    if (header & 1) {  // bit-packed, in groups of 8 values
      const std::uint64_t run_bytes = (header >> 1) * static_cast<std::uint64_t>(width);
      const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>((header >> 1) * 8, left));
      if ((static_cast<std::uint64_t>(n) * static_cast<std::uint64_t>(width) + 7) / 8 > data.size() - pos)
        return "a bit-packed run of the RLE data runs past its end";
      for (std::size_t k = 0; k < n; ++k) {
        const std::uint64_t bit = static_cast<std::uint64_t>(k) * static_cast<std::uint64_t>(width);
        const std::size_t at = pos + static_cast<std::size_t>(bit / 8);
        std::uint64_t window = 0;
        for (std::size_t b = 0; b < 8 && at + b < data.size(); ++b)
          window |= static_cast<std::uint64_t>(data[at + b]) << (8 * b);
        const std::uint64_t mask = width == 0 ? 0 : (std::uint64_t{1} << width) - 1;
        put(static_cast<std::uint32_t>((window >> (bit % 8)) & mask), 1);
      }
      pos += static_cast<std::size_t>(std::min<std::uint64_t>(run_bytes, data.size() - pos));
      done += n;
    } else {  // one value repeated
      if (value_bytes > data.size() - pos) return "a run of the RLE data runs past its end";
      std::uint32_t v = 0;
      for (std::size_t b = 0; b < value_bytes; ++b) v |= static_cast<std::uint32_t>(data[pos + b]) << (8 * b);
      pos += value_bytes;
      const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(header >> 1, left));
      if (n > 0) put(v, n);
      done += n;
    }
  }
  return {};
}

int bitWidth(int max_level) {
  int w = 0;
  while ((1 << w) <= max_level) ++w;
  return w;
}

// A page's (or a dictionary's) values: numbers or byte strings, as the leaf holds.
struct Values {
  std::vector<double> numbers;
  std::vector<std::string> bytes;
  std::size_t size(bool is_bytes) const { return is_bytes ? bytes.size() : numbers.size(); }
};

// What a read needs of the open file.
struct FileData {
  std::string path;
  std::uint64_t size = 0;
  std::uint64_t dataEnd = 0;  // where the footer begins: column chunks lie before it
  std::int64_t rows = 0;
  std::vector<Leaf> leaves;
  std::vector<GroupMeta> groups;
  std::vector<ParquetRowGroup> rowGroups;
  std::vector<std::pair<std::string, std::string>> keyValues;

  [[noreturn]] void fail(const std::string& problem) const { throw InputError(InputLocation{path, 0, 0, {}}, problem); }
  // Reads the footer from `in` (the file, `size` bytes): the schema's leaves, the row groups.
  void readFooter(std::ifstream& in);
  void checkGroups(FileMeta& meta);
  // The leaf named `name`; throws InputError, naming the columns, when there is none.
  std::size_t leafIndex(const std::string& name) const;
  void checkGroup(std::size_t group) const;
};

class ChunkReader {
 public:
  ChunkReader(const FileData& file, std::size_t leaf, std::size_t group, ParquetColumn& out, std::uint64_t& budget)
      : f_(file),
        leaf_(file.leaves[leaf]),
        meta_(file.groups[group].chunks[leaf]),
        group_(group),
        rows_expected_(file.groups[group].rows),
        out_(out),
        budget_(budget) {}

  void read(std::ifstream& in);

 private:
  [[noreturn]] void fail(const std::string& problem) const {
    std::string where = "row group " + std::to_string(group_) + ", column " + printable(leaf_.name);
    if (page_at_ >= 0) where += ", page at byte " + std::to_string(page_at_);
    throw InputError(InputLocation{f_.path, 0, 0, where}, problem);
  }
  // Takes `count` times `each` bytes from the read's budget.
  void take(std::uint64_t count, std::uint64_t each = 1) {
    if (each != 0 && count > budget_ / each)
      fail("the column's pages expand to more than 256 MiB plus 256 times the file's size (a decompression bomb)");
    budget_ -= count * each;
  }
  void checkChunk() const;
  std::span<const std::uint8_t> decompressed(std::span<const std::uint8_t> raw, std::uint64_t size);
  void dictionaryPage(const PageHeader& h, std::span<const std::uint8_t> raw);
  std::int64_t dataPage(const PageHeader& h, std::span<const std::uint8_t> raw, std::int64_t left);
  std::span<const std::uint8_t> levels(std::span<const std::uint8_t> data, bool v1, int max, std::size_t count,
                                       std::vector<std::uint8_t>& out, const char* what);
  void decodeValues(int encoding, std::span<const std::uint8_t> data, std::size_t count, Values& out);
  void plain(std::span<const std::uint8_t> data, std::size_t count, Values& out);
  void assemble(const std::vector<std::uint8_t>& rep, const std::vector<std::uint8_t>& def, std::size_t count,
                Values& values);
  double number(const std::uint8_t* p) const;

  const FileData& f_;
  const Leaf& leaf_;
  const ChunkMeta& meta_;
  std::size_t group_;
  std::int64_t rows_expected_;
  ParquetColumn& out_;
  std::uint64_t& budget_;
  std::int64_t page_at_ = -1;
  std::int64_t rows_ = 0;
  bool has_dictionary_ = false;
  bool seen_data_ = false;
  Values dictionary_;
  std::vector<std::uint8_t> scratch_;
};

void ChunkReader::checkChunk() const {
  if (meta_.external) fail("the column chunk is in another file, which this reader does not follow");
  if (meta_.encrypted) fail("the column chunk is encrypted, which this reader does not read");
  if (!meta_.hasMeta) fail("the column chunk has no metadata");
  if (meta_.type != leaf_.type)
    fail(std::string("the column chunk holds ") + physicalName(meta_.type) + " values, the schema says " +
         physicalName(leaf_.type));
  if (meta_.codec != kUncompressed && meta_.codec != kSnappy && meta_.codec != kGzip && meta_.codec != kZstd)
    fail(codecName(meta_.codec) + " compression is not read by this reader (only SNAPPY, ZSTD, GZIP or none)");
  if (meta_.numValues < 0) fail("the column chunk counts " + std::to_string(meta_.numValues) + " values");
}

void ChunkReader::read(std::ifstream& in) {
  checkChunk();
  std::int64_t start = meta_.dataPageOffset;
  if (meta_.dictionaryPageOffset > 0 && meta_.dictionaryPageOffset < start) start = meta_.dictionaryPageOffset;
  const std::uint64_t end = f_.dataEnd;
  if (start < 4 || meta_.totalCompressed < 0 || static_cast<std::uint64_t>(start) > end ||
      static_cast<std::uint64_t>(meta_.totalCompressed) > end - static_cast<std::uint64_t>(start))
    fail("the column chunk (" + std::to_string(meta_.totalCompressed) + " bytes at byte " + std::to_string(start) +
         ") lies outside the file's data (bytes 4 to " + std::to_string(end) + ")");
  std::vector<std::uint8_t> chunk(static_cast<std::size_t>(meta_.totalCompressed));
  in.clear();
  in.seekg(static_cast<std::streamoff>(start));
  if (!in.read(reinterpret_cast<char*>(chunk.data()), static_cast<std::streamsize>(chunk.size())))
    fail("the column chunk cannot be read");
  std::size_t pos = 0;
  std::int64_t seen = 0;
  while (seen < meta_.numValues) {
    page_at_ = start + static_cast<std::int64_t>(pos);
    if (pos >= chunk.size())
      fail("the column chunk ends after " + std::to_string(seen) + " of its " + std::to_string(meta_.numValues) +
           " values");
    CompactReader r(std::span<const std::uint8_t>(chunk).subspan(pos));
    PageHeader h;
    try {
      h = readPageHeader(r);
    } catch (const ThriftError& e) {
      fail(std::string("the page header does not decode: ") + e.what());
    }
    pos += r.position();
    if (h.compressed < 0 || h.uncompressed < 0) fail("the page header gives no sizes (or negative ones)");
    if (static_cast<std::uint64_t>(h.compressed) > chunk.size() - pos)
      fail("the page's " + std::to_string(h.compressed) + " bytes run past the column chunk's end (" +
           std::to_string(chunk.size() - pos) + " bytes left)");
    const std::span<const std::uint8_t> raw(chunk.data() + pos, static_cast<std::size_t>(h.compressed));
    pos += static_cast<std::size_t>(h.compressed);
    if (h.type == kDictionaryPage) {
      dictionaryPage(h, raw);
    } else if (h.type == kDataPage || h.type == kDataPageV2) {
      seen += dataPage(h, raw, meta_.numValues - seen);
    }  // index pages (and page types of later versions) hold no values
  }
  page_at_ = -1;
  if (rows_ != rows_expected_)
    fail("the column holds " + std::to_string(rows_) + " rows, its row group " + std::to_string(rows_expected_));
}

std::span<const std::uint8_t> ChunkReader::decompressed(std::span<const std::uint8_t> raw, std::uint64_t size) {
  if (meta_.codec == kUncompressed) {
    if (raw.size() != size)
      fail("the uncompressed page holds " + std::to_string(raw.size()) + " bytes, its header says " +
           std::to_string(size));
    return raw;
  }
  take(size);
  static const char* names[] = {"", "snappy", "gzip", "", "", "", "zstd"};
  const std::string problem = detail::decompress(names[meta_.codec], raw, size, scratch_, "page");
  if (!problem.empty()) fail(problem);
  return scratch_;
}

void ChunkReader::dictionaryPage(const PageHeader& h, std::span<const std::uint8_t> raw) {
  if (!h.hasBody) fail("the dictionary page has no dictionary page header");
  if (has_dictionary_ || seen_data_) fail("a dictionary page after the column chunk's first page");
  if (h.encoding != kPlain && h.encoding != kPlainDictionary)
    fail("the dictionary page's encoding " + encodingName(h.encoding) + " is not PLAIN");
  const std::span<const std::uint8_t> data = decompressed(raw, static_cast<std::uint64_t>(h.uncompressed));
  if (h.numValues < 0) fail("the dictionary page counts " + std::to_string(h.numValues) + " values");
  take(static_cast<std::uint64_t>(h.numValues), kValueCost);
  plain(data, static_cast<std::size_t>(h.numValues), dictionary_);
  has_dictionary_ = true;
}

// Reads the levels of `count` values from the front of `data` (v1: after their 4-byte length; v2:
// `data` is exactly the levels) into `out`; returns what follows them.
std::span<const std::uint8_t> ChunkReader::levels(std::span<const std::uint8_t> data, bool v1, int max,
                                                  std::size_t count, std::vector<std::uint8_t>& out, const char* what) {
  out.assign(count, 0);
  if (max == 0) return data;
  std::span<const std::uint8_t> run = data;
  if (v1) {
    if (data.size() < 4) fail(std::string("the page ends before its ") + what + " levels' length");
    const std::uint32_t n = le32(data.data());
    if (n > data.size() - 4)
      fail(std::string("the ") + what + " levels' " + std::to_string(n) + " bytes run past the page's end");
    run = data.subspan(4, n);
    data = data.subspan(4 + n);
  }
  std::size_t at = 0;
  bool too_high = false;
  const std::string problem = decodeHybrid(run, bitWidth(max), count, [&](std::uint32_t v, std::size_t times) {
    too_high = too_high || v > static_cast<std::uint32_t>(max);
    std::fill_n(out.begin() + static_cast<std::ptrdiff_t>(at), times,
                static_cast<std::uint8_t>(std::min<std::uint32_t>(v, 255)));
    at += times;
  });
  if (!problem.empty()) fail(std::string("the ") + what + " levels: " + problem);
  if (too_high) fail(std::string("a ") + what + " level above the column's " + std::to_string(max));
  return data;
}

std::int64_t ChunkReader::dataPage(const PageHeader& h, std::span<const std::uint8_t> raw, std::int64_t left) {
  if (!h.hasBody) fail("the data page has no data page header");
  if (h.numValues < 0 || h.numValues > left)
    fail("the page counts " + std::to_string(h.numValues) + " values, more than the column chunk's " +
         std::to_string(left) + " left");
  seen_data_ = true;
  const std::size_t count = static_cast<std::size_t>(h.numValues);
  take(count, kValueCost);
  std::vector<std::uint8_t> rep, def;
  std::span<const std::uint8_t> values;
  if (h.type == kDataPage) {
    if (leaf_.maxRep > 0 && h.repEncoding != kRle)
      fail("the repetition levels' encoding " + encodingName(h.repEncoding) + " is not read by this reader (RLE)");
    if (leaf_.maxDef > 0 && h.defEncoding != kRle)
      fail("the definition levels' encoding " + encodingName(h.defEncoding) + " is not read by this reader (RLE)");
    std::span<const std::uint8_t> data = decompressed(raw, static_cast<std::uint64_t>(h.uncompressed));
    data = levels(data, true, leaf_.maxRep, count, rep, "repetition");
    values = levels(data, true, leaf_.maxDef, count, def, "definition");
  } else {
    // v2: the levels come first, never compressed; then the values, compressed if the page says so.
    if (h.repLength < 0 || h.defLength < 0 || static_cast<std::uint64_t>(h.repLength + h.defLength) > raw.size() ||
        h.repLength + h.defLength > h.uncompressed)
      fail("the page's level lengths (" + std::to_string(h.repLength) + " and " + std::to_string(h.defLength) +
           " bytes) do not fit in the page");
    const std::size_t rl = static_cast<std::size_t>(h.repLength), dl = static_cast<std::size_t>(h.defLength);
    levels(raw.subspan(0, rl), false, leaf_.maxRep, count, rep, "repetition");
    levels(raw.subspan(rl, dl), false, leaf_.maxDef, count, def, "definition");
    const std::span<const std::uint8_t> rest = raw.subspan(rl + dl);
    const std::uint64_t size = static_cast<std::uint64_t>(h.uncompressed) - rl - dl;
    if (h.isCompressed) {
      values = decompressed(rest, size);
    } else if (rest.size() != size) {
      fail("the page's values hold " + std::to_string(rest.size()) + " bytes, its header says " + std::to_string(size));
    } else {
      values = rest;
    }
  }
  const std::size_t present =
      leaf_.maxDef == 0
          ? count
          : static_cast<std::size_t>(std::count(def.begin(), def.end(), static_cast<std::uint8_t>(leaf_.maxDef)));
  Values decoded;
  decodeValues(h.encoding, values, present, decoded);
  assemble(rep, def, count, decoded);
  return h.numValues;
}

void ChunkReader::decodeValues(int encoding, std::span<const std::uint8_t> data, std::size_t count, Values& out) {
  if (encoding == kPlain) return plain(data, count, out);
  if (encoding == kRle && leaf_.type == kBoolean) {
    // RLE booleans: their length in 4 bytes, then the hybrid at one bit a value.
    if (data.size() < 4 || le32(data.data()) > data.size() - 4) fail("the page's RLE booleans run past its end");
    out.numbers.reserve(count);
    const std::string problem =
        decodeHybrid(data.subspan(4, le32(data.data())), 1, count,
                     [&](std::uint32_t v, std::size_t n) { out.numbers.insert(out.numbers.end(), n, v & 1); });
    if (!problem.empty()) fail("the page's booleans: " + problem);
    return;
  }
  if (encoding != kPlainDictionary && encoding != kRleDictionary)
    fail("the page's encoding " + encodingName(encoding) +
         " is not read by this reader (only PLAIN, PLAIN_DICTIONARY, RLE_DICTIONARY and RLE for booleans)");
  if (!has_dictionary_) fail("a dictionary-encoded page, and no dictionary page before it");
  if (count == 0) return;
  if (data.empty() || data[0] > 32) fail("the page's dictionary indices have no bit width (or one above 32)");
  const bool bytes = leaf_.isBytes();
  const std::size_t entries = dictionary_.size(bytes);
  bool outside = false;
  const std::string problem = decodeHybrid(data.subspan(1), data[0], count, [&](std::uint32_t i, std::size_t n) {
    if (i >= entries) {
      outside = true;
      return;
    }
    if (!bytes) {
      out.numbers.insert(out.numbers.end(), n, dictionary_.numbers[i]);
      return;
    }
    // Copies of a dictionary's strings cost the budget too: a run of one index could copy a long
    // string without limit.
    const std::string& s = dictionary_.bytes[i];
    take(n, s.size());
    out.bytes.insert(out.bytes.end(), n, s);
  });
  if (!problem.empty()) fail("the page's dictionary indices: " + problem);
  if (outside) fail("a dictionary index past the dictionary's " + std::to_string(entries) + " values");
}

double ChunkReader::number(const std::uint8_t* p) const {
  switch (leaf_.type) {
    case kInt32: {
      const std::uint32_t u = le32(p);
      return (leaf_.isUnsigned ? static_cast<double>(u) : static_cast<double>(static_cast<std::int32_t>(u))) /
             leaf_.divisor;
    }
    case kInt64: {
      const std::uint64_t u = le64(p);
      return (leaf_.isUnsigned ? static_cast<double>(u) : static_cast<double>(static_cast<std::int64_t>(u))) /
             leaf_.divisor;
    }
    case kFloat: {
      const std::uint32_t u = le32(p);
      float v;
      std::memcpy(&v, &u, 4);
      return v;
    }
    default: {
      const std::uint64_t u = le64(p);
      double v;
      std::memcpy(&v, &u, 8);
      return v;
    }
  }
}

void ChunkReader::plain(std::span<const std::uint8_t> data, std::size_t count, Values& out) {
  const auto short_of = [&](std::size_t i) {
    fail("the page's PLAIN values end after " + std::to_string(i) + " of " + std::to_string(count));
  };
  if (leaf_.type == kBoolean) {
    if ((count + 7) / 8 > data.size()) short_of(data.size() * 8);
    out.numbers.reserve(count);
    for (std::size_t i = 0; i < count; ++i) out.numbers.push_back((data[i / 8] >> (i % 8)) & 1);
  } else if (leaf_.type == kByteArray) {
    std::size_t pos = 0;
    out.bytes.reserve(std::min(count, data.size() / 4));
    for (std::size_t i = 0; i < count; ++i) {
      if (data.size() - pos < 4 || le32(data.data() + pos) > data.size() - pos - 4) short_of(i);
      const std::uint32_t n = le32(data.data() + pos);
      out.bytes.emplace_back(reinterpret_cast<const char*>(data.data() + pos + 4), n);
      pos += 4 + n;
    }
  } else if (leaf_.type == kFixedLenByteArray) {
    const std::uint64_t n = static_cast<std::uint64_t>(leaf_.typeLength);
    if (count > 0 && n > data.size() / count) short_of(static_cast<std::size_t>(data.size() / n));
    out.bytes.reserve(count);
    for (std::size_t i = 0; i < count; ++i)
      out.bytes.emplace_back(reinterpret_cast<const char*>(data.data() + i * n), static_cast<std::size_t>(n));
  } else {
    const std::size_t width = leaf_.type == kInt32 || leaf_.type == kFloat ? 4 : 8;
    if (count > data.size() / width) short_of(data.size() / width);
    out.numbers.reserve(count);
    for (std::size_t i = 0; i < count; ++i) out.numbers.push_back(number(data.data() + i * width));
  }
}

// Hands the page's values to rows by their levels: a repetition level of 0 starts a row; a
// definition level below the list's leaves the row's list empty (or null); below the leaf's own,
// a null value.
void ChunkReader::assemble(const std::vector<std::uint8_t>& rep, const std::vector<std::uint8_t>& def,
                           std::size_t count, Values& values) {
  const bool bytes = leaf_.isBytes();
  std::size_t next = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t held = bytes ? out_.bytes.size() : out_.numbers.size();
    if (leaf_.maxRep == 0 || rep[i] == 0) {
      if (rows_ >= rows_expected_)
        fail("the page holds more rows than its row group's " + std::to_string(rows_expected_));
      out_.rowStart.push_back(held);
      ++rows_;
    } else if (rows_ == 0) {
      fail("the column chunk's first value continues a row (its repetition level is not 0)");
    }
    if (leaf_.maxRep > 0 && def[i] < leaf_.listDef) continue;  // an empty or null list
    if (def[i] == leaf_.maxDef) {
      if (bytes)
        out_.bytes.push_back(std::move(values.bytes[next++]));
      else
        out_.numbers.push_back(values.numbers[next++]);
    } else if (bytes) {
      out_.bytes.emplace_back();
    } else {
      out_.numbers.push_back(std::numeric_limits<double>::quiet_NaN());
    }
  }
}

void FileData::readFooter(std::ifstream& in) {
  std::uint8_t head[4] = {}, tail[8] = {};
  if (size < 12)
    fail("not a Parquet file, or cut short: " + std::to_string(size) + " bytes, fewer than the 12 of the smallest");
  in.read(reinterpret_cast<char*>(head), 4);
  in.seekg(static_cast<std::streamoff>(size - 8));
  in.read(reinterpret_cast<char*>(tail), 8);
  if (!in) fail("cannot be read");
  if (std::memcmp(head, kMagic, 4) != 0) fail("not a Parquet file (its first 4 bytes are not PAR1)");
  if (std::memcmp(tail + 4, kEncryptedMagic, 4) == 0)
    fail("an encrypted footer (PARE): encrypted Parquet files are not read by this reader");
  if (std::memcmp(tail + 4, kMagic, 4) != 0)
    fail("cut short or damaged: its last 4 bytes are not PAR1 (a Parquet file ends with its footer and PAR1)");
  const std::uint32_t length = le32(tail);
  if (length > size - 12)
    fail("the footer's length (" + std::to_string(length) + " bytes) is more than the file holds before it (" +
         std::to_string(size - 12) + ")");
  dataEnd = size - 8 - length;
  std::vector<std::uint8_t> footer(length);
  in.seekg(static_cast<std::streamoff>(dataEnd));
  if (!in.read(reinterpret_cast<char*>(footer.data()), static_cast<std::streamsize>(length))) fail("cannot be read");
  FileMeta meta;
  try {
    CompactReader r(footer);
    meta = readFileMetaData(r);
  } catch (const ThriftError& e) {
    fail(std::string("the footer (at byte ") + std::to_string(dataEnd) + ") does not decode: " + e.what());
  }
  if (meta.encrypted) fail("encrypted columns: encrypted Parquet files are not read by this reader");
  leaves = SchemaWalk(path, meta.schema).leaves();
  checkGroups(meta);
  keyValues = std::move(meta.keyValues);
}

void FileData::checkGroups(FileMeta& meta) {
  for (std::size_t g = 0; g < meta.groups.size(); ++g) {
    const GroupMeta& group = meta.groups[g];
    const std::string which = "row group " + std::to_string(g);
    if (group.rows < 0) fail(which + " gives no row count (or a negative one)");
    if (group.chunks.size() != leaves.size())
      fail(which + " has " + std::to_string(group.chunks.size()) + " column chunks, the schema " +
           std::to_string(leaves.size()) + " columns");
    if (group.rows > std::numeric_limits<std::int64_t>::max() - rows) fail(which + ": the row count overflows");
    rowGroups.push_back(ParquetRowGroup{group.rows, rows});
    rows += group.rows;
  }
  if (meta.rows != rows)
    fail("the footer counts " + std::to_string(meta.rows) + " rows, its row groups " + std::to_string(rows));
  groups = std::move(meta.groups);
}

std::size_t FileData::leafIndex(const std::string& name) const {
  for (std::size_t i = 0; i < leaves.size(); ++i)
    if (leaves[i].name == name) return i;
  std::string names;
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    if (names.size() > 300) {
      names += ", ... (" + std::to_string(leaves.size()) + " in all)";
      break;
    }
    names += (i ? ", " : "") + printable(leaves[i].name);
  }
  fail("no column " + printable(name) + "; the columns are " + (names.empty() ? "none" : names));
}

void FileData::checkGroup(std::size_t group) const {
  if (group >= groups.size())
    fail("no row group " + std::to_string(group) + "; the file has " + std::to_string(groups.size()));
}

std::optional<std::pair<std::int64_t, std::int64_t>> integerRange(const FileData& file, const std::string& name,
                                                                  std::size_t group) {
  // A column or row group the file does not have has no statistics either.
  const auto it = std::find_if(file.leaves.begin(), file.leaves.end(), [&](const Leaf& l) { return l.name == name; });
  if (it == file.leaves.end() || group >= file.groups.size()) return std::nullopt;
  const std::size_t index = static_cast<std::size_t>(it - file.leaves.begin());
  const Leaf& leaf = *it;
  if ((leaf.type != kInt32 && leaf.type != kInt64) || leaf.divisor != 1) return std::nullopt;
  const Statistics& s = file.groups[group].chunks[index].stats;
  // The deprecated min and max are in signed order: right for signed integers only.
  const std::optional<std::string>& lo = s.minValue ? s.minValue : leaf.isUnsigned ? s.minValue : s.min;
  const std::optional<std::string>& hi = s.maxValue ? s.maxValue : leaf.isUnsigned ? s.maxValue : s.max;
  const std::size_t width = leaf.type == kInt32 ? 4 : 8;
  if (!lo || !hi || lo->size() != width || hi->size() != width) return std::nullopt;
  const auto value = [&](const std::string& b) -> std::optional<std::int64_t> {
    const auto* p = reinterpret_cast<const std::uint8_t*>(b.data());
    if (width == 4) return leaf.isUnsigned ? std::int64_t{le32(p)} : std::int64_t{static_cast<std::int32_t>(le32(p))};
    const std::uint64_t u = le64(p);
    if (leaf.isUnsigned && u > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()))
      return std::nullopt;
    return static_cast<std::int64_t>(u);
  };
  const auto min = value(*lo), max = value(*hi);
  if (!min || !max || *min > *max) return std::nullopt;
  return std::make_pair(*min, *max);
}

ParquetColumn readColumn(const FileData& m, const std::string& name, const std::vector<std::size_t>& groups) {
  const std::size_t leaf = m.leafIndex(name);
  if (!m.leaves[leaf].refused.empty()) m.fail(m.leaves[leaf].refused);
  std::vector<std::size_t> order = groups;
  if (order.empty())
    for (std::size_t g = 0; g < m.groups.size(); ++g) order.push_back(g);
  for (const std::size_t g : order) m.checkGroup(g);
  ParquetColumn out;
  out.name = name;
  out.isBytes = m.leaves[leaf].isBytes();
  out.isList = m.leaves[leaf].maxRep > 0;
  std::ifstream in(m.path, std::ios::binary);
  if (!in) m.fail("cannot be opened");
  // Each read has its budget: a file read column by column may expand to that much per column.
  std::uint64_t budget = detail::decompressBudget(m.size);
  for (const std::size_t g : order) ChunkReader(m, leaf, g, out, budget).read(in);
  out.rowStart.push_back(out.isBytes ? out.bytes.size() : out.numbers.size());
  return out;
}

}  // namespace detail::parquet

struct ParquetFile::Impl : detail::parquet::FileData {};

ParquetFile::ParquetFile(const std::string& path) : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  std::ifstream in(path, std::ios::binary);
  if (!in) impl_->fail("cannot be opened");
  in.seekg(0, std::ios::end);
  const std::streamoff end = in.tellg();
  in.seekg(0);
  if (end < 0) impl_->fail("cannot be read");
  impl_->size = static_cast<std::uint64_t>(end);
  impl_->readFooter(in);
}

ParquetFile::~ParquetFile() = default;
ParquetFile::ParquetFile(ParquetFile&&) noexcept = default;
ParquetFile& ParquetFile::operator=(ParquetFile&&) noexcept = default;

const std::string& ParquetFile::path() const { return impl_->path; }
std::int64_t ParquetFile::rows() const { return impl_->rows; }
const std::vector<ParquetRowGroup>& ParquetFile::rowGroups() const { return impl_->rowGroups; }

std::vector<std::string> ParquetFile::columns() const {
  std::vector<std::string> out;
  for (const auto& l : impl_->leaves) out.push_back(l.name);
  return out;
}

bool ParquetFile::hasColumn(const std::string& name) const {
  return std::any_of(impl_->leaves.begin(), impl_->leaves.end(), [&](const auto& l) { return l.name == name; });
}

std::optional<std::string> ParquetFile::metadata(const std::string& key) const {
  for (const auto& [k, v] : impl_->keyValues)
    if (k == key) return v;
  return std::nullopt;
}

std::optional<std::pair<std::int64_t, std::int64_t>> ParquetFile::integerRange(const std::string& name,
                                                                               std::size_t group) const {
  return detail::parquet::integerRange(*impl_, name, group);
}

ParquetColumn ParquetFile::read(const std::string& name, const std::vector<std::size_t>& groups) const {
  return detail::parquet::readColumn(*impl_, name, groups);
}

}  // namespace kccd::logs
