// The Parquet reader (kccd::logs::ParquetFile) against files other projects' writers made:
// tests/datasets/write_parquet.mjs writes one LeRobot-like table (a float32 list like
// observation.state, a fixed-size list, float64, int64 and int32 scalars, a boolean, strings, a
// struct of PNG bytes and a path, fixed-length bytes, nulls, row groups of 7 rows) with
// parquet-wasm (arrow-rs) in every compression, page version and dictionary setting it offers, and
// with hyparquet-writer; legacy two-level lists; and files with an encoding or a layout this reader
// refuses. truth.json lists what each file holds. Also: every cut of a small file and every flipped
// byte reads or gives one InputError line naming the file, never a crash.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <nlohmann/json.hpp>

#include "kccd/input_error.hpp"
#include "kccd/logs/parquet_reader.hpp"
#include "support/files.hpp"
#include "support/run_program.hpp"

namespace {

namespace fs = std::filesystem;
using kccd::InputError;
using kccd::logs::ParquetColumn;
using kccd::logs::ParquetFile;
using kccd::testing::readText;
using kccd::testing::runProgram;
using nlohmann::json;

// The files of the small set (5 rows in row groups of 2): the cut and flipped-byte tests' inputs.
const char* const kSmall[] = {"pw_snappy_v1_dict.parquet", "pw_zstd_v2_plain.parquet", "hy_gzip_plain.parquet",
                              "hy_none_dict.parquet"};

std::string unhex(const std::string& hex) {
  std::string out;
  for (std::size_t i = 0; i + 1 < hex.size(); i += 2)
    out.push_back(static_cast<char>(std::stoi(hex.substr(i, 2), nullptr, 16)));
  return out;
}

// The contract of every error: one line that starts with the file's name.
void expectOneLine(const std::string& message, const std::string& path) {
  EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
}

// Opens `path` and reads every column over every row group; false when it throws InputError
// (checked against the contract), true when it reads.
bool readsWhole(const std::string& path) {
  try {
    const ParquetFile f(path);
    for (const std::string& c : f.columns()) {
      const ParquetColumn col = f.read(c);
      EXPECT_EQ(static_cast<std::int64_t>(col.rows()), f.rows());
    }
    return true;
  } catch (const InputError& e) {
    expectOneLine(e.what(), path);
    return false;
  }
}

class ParquetFixtures : public ::testing::Test {
 protected:
  // The writers run once per process (node and tests/datasets/node_modules: scripts/install-deps.sh --tests).
  static void SetUpTestSuite() {
    dir_ = kccd::testing::scratchFolder("test_parquet") / "datasets";
    fs::create_directories(dir_);
    const std::string writer = std::string(KCCD_NODE) + " " + KCCD_SOURCE_DIR + "/tests/datasets/write_parquet.mjs ";
    const auto r = runProgram(writer + dir_.string(), true);
    ASSERT_EQ(r.code, 0) << "the fixture writer failed (npm ci in tests/datasets?): " << r.out;
    std::string only;
    for (const char* name : kSmall) {
      if (!only.empty()) only += ',';
      only += name;
    }
    const auto s = runProgram(
        "KCCD_PARQUET_ROWS=5 KCCD_PARQUET_GROUP=2 KCCD_PARQUET_ONLY=" + only + " " + writer + (dir_ / "small").string(),
        true);
    ASSERT_EQ(s.code, 0) << "the small fixtures' writer failed: " << s.out;
    truth_ = json::parse(readText((dir_ / "truth.json").string()));
  }
  static std::string file(const std::string& name) { return (dir_ / name).string(); }
  static std::string small(const std::string& name) { return (dir_ / "small" / name).string(); }
  // The files whose every column reads.
  static std::vector<std::string> readable() {
    std::vector<std::string> out;
    for (const auto& [name, f] : truth_["files"].items())
      if (!f.contains("refused") && !f.contains("refusedLayout")) out.push_back(name);
    return out;
  }
  // Checks `c` against truth.json's column `name`, over the truth's rows `rows` in that order.
  static void expectColumn(const ParquetColumn& c, const std::string& name, const std::vector<std::size_t>& rows) {
    const json& spec = truth_["columns"][name];
    EXPECT_EQ(c.name, name);
    EXPECT_EQ(c.isBytes, spec["bytes"].get<bool>());
    EXPECT_EQ(c.isList, spec["list"].get<bool>());
    ASSERT_EQ(c.rows(), rows.size());
    ASSERT_EQ(c.rowStart.back(), c.isBytes ? c.bytes.size() : c.numbers.size());
    for (std::size_t r = 0; r < rows.size(); ++r) {
      const json& want = spec["rows"][rows[r]];
      ASSERT_EQ(c.rowStart[r + 1] - c.rowStart[r], want.size()) << name << " row " << rows[r];
      for (std::size_t k = 0; k < want.size(); ++k) {
        const std::size_t at = c.rowStart[r] + k;
        if (c.isBytes) {
          EXPECT_EQ(c.bytes[at], unhex(want[k].get<std::string>())) << name << " row " << rows[r];
        } else if (want[k].is_null()) {
          EXPECT_TRUE(std::isnan(c.numbers[at])) << name << " row " << rows[r] << ": " << c.numbers[at];
        } else {
          // Exact: a float32 is written as the double it rounds to, and read back as that double.
          EXPECT_EQ(c.numbers[at], want[k].get<double>()) << name << " row " << rows[r] << " value " << k;
        }
      }
    }
  }
  static std::vector<std::size_t> allRows() {
    std::vector<std::size_t> rows(truth_["rows"].get<std::size_t>());
    for (std::size_t i = 0; i < rows.size(); ++i) rows[i] = i;
    return rows;
  }
  static inline fs::path dir_;
  static inline json truth_;
};

TEST_F(ParquetFixtures, EveryFileReadsAsWritten) {
  const std::vector<std::string> names = readable();
  EXPECT_EQ(names.size(), 23u);  // 16 parquet-wasm, 6 hyparquet-writer, the legacy lists
  for (const std::string& name : names) {
    SCOPED_TRACE(name);
    const json& t = truth_["files"][name];
    const ParquetFile f(file(name));
    EXPECT_EQ(f.path(), file(name));
    EXPECT_EQ(f.rows(), truth_["rows"].get<std::int64_t>());
    EXPECT_EQ(f.columns(), t["columns"].get<std::vector<std::string>>());
    for (const auto& [key, value] : t["metadata"].items()) EXPECT_EQ(f.metadata(key), value.get<std::string>());
    for (const std::string& c : t["columns"].get<std::vector<std::string>>()) {
      SCOPED_TRACE(c);
      EXPECT_TRUE(f.hasColumn(c));
      expectColumn(f.read(c), c, allRows());
    }
  }
}

TEST_F(ParquetFixtures, TheMatrixOfWritersAndSettingsIsCovered) {
  std::set<std::string> seen;
  for (const auto& [name, t] : truth_["files"].items())
    if (t.contains("compression") && !t.contains("refused"))
      seen.insert(t["writer"].get<std::string>() + " " + t["compression"].get<std::string>() + " v" +
                  std::to_string(t["pageVersion"].get<int>()) + (t["dictionary"].get<bool>() ? " dict" : " plain"));
  for (const char* c : {"none", "snappy", "zstd", "gzip"})
    for (const char* v : {" v1", " v2"})
      for (const char* d : {" dict", " plain"})
        EXPECT_TRUE(seen.count(std::string("parquet-wasm ") + c + v + d)) << c << v << d;
  for (const char* c : {"none", "snappy", "gzip"})
    for (const char* d : {" dict", " plain"}) EXPECT_TRUE(seen.count(std::string("hyparquet-writer ") + c + " v2" + d));
}

TEST_F(ParquetFixtures, ColumnNamesLeaveOutListLevels) {
  const std::vector<std::string> arrow = {"observation.state",
                                          "action",
                                          "timestamp",
                                          "frame_index",
                                          "episode_index",
                                          "index",
                                          "task_index",
                                          "next.done",
                                          "task",
                                          "observation.images.top/bytes",
                                          "observation.images.top/path",
                                          "tag"};
  // Arrow's lists are `name/list/item`, hyparquet-writer's `name/list/element`.
  EXPECT_EQ(ParquetFile(file("pw_none_v1_plain.parquet")).columns(), arrow);
  std::vector<std::string> hy = arrow;
  hy.erase(hy.begin() + 1);
  EXPECT_EQ(ParquetFile(file("hy_none_plain.parquet")).columns(), hy);
  // Two-level lists: `legacy (LIST) / repeated element` and a bare repeated field.
  EXPECT_EQ(ParquetFile(file("hy_legacy_lists.parquet")).columns(),
            (std::vector<std::string>{"index", "legacy", "legacy_bare"}));
  EXPECT_FALSE(ParquetFile(file("hy_none_plain.parquet")).hasColumn("observation.state/list/element"));
}

TEST_F(ParquetFixtures, RowGroupsReadInTheOrderAsked) {
  for (const char* name : {"pw_snappy_v1_dict.parquet", "pw_gzip_v2_plain.parquet", "hy_snappy_dict.parquet"}) {
    SCOPED_TRACE(name);
    const ParquetFile f(file(name));
    ASSERT_EQ(f.rowGroups().size(), truth_["groups"].size());
    for (std::size_t g = 0; g < f.rowGroups().size(); ++g) {
      EXPECT_EQ(f.rowGroups()[g].rows, truth_["groups"][g]["rows"].get<std::int64_t>());
      EXPECT_EQ(f.rowGroups()[g].firstRow, truth_["groups"][g]["first"].get<std::int64_t>());
    }
    std::vector<std::size_t> rows;
    for (const std::size_t g : {2, 0})
      for (std::int64_t r = 0; r < f.rowGroups()[g].rows; ++r)
        rows.push_back(static_cast<std::size_t>(f.rowGroups()[g].firstRow + r));
    for (const char* c : {"observation.state", "index", "task", "observation.images.top/bytes", "next.done"}) {
      SCOPED_TRACE(c);
      expectColumn(f.read(c, {2, 0}), c, rows);
    }
    // The last group (a short one) alone.
    const std::size_t last = f.rowGroups().size() - 1;
    const ParquetColumn tail = f.read("timestamp", {last});
    EXPECT_EQ(static_cast<std::int64_t>(tail.rows()), f.rowGroups()[last].rows);
  }
}

TEST_F(ParquetFixtures, IntegerRangesAreTheWritersStatistics) {
  for (const std::string& name : readable()) {
    SCOPED_TRACE(name);
    const ParquetFile f(file(name));
    for (const auto& [column, groups] : truth_["files"][name]["integerRanges"].items()) {
      for (std::size_t g = 0; g < groups.size(); ++g) {
        const auto range = f.integerRange(column, g);
        ASSERT_TRUE(range.has_value()) << column << " group " << g;
        EXPECT_EQ(range->first, groups[g][0].get<std::int64_t>()) << column << " group " << g;
        EXPECT_EQ(range->second, groups[g][1].get<std::int64_t>()) << column << " group " << g;
      }
    }
    if (f.hasColumn("timestamp")) {
      EXPECT_FALSE(f.integerRange("timestamp", 0).has_value());  // not an integer
    }
  }
}

TEST_F(ParquetFixtures, MetadataByKey) {
  const ParquetFile pw(file("pw_zstd_v1_dict.parquet"));
  EXPECT_TRUE(pw.metadata("ARROW:schema").has_value());  // arrow-rs stores the Arrow schema
  EXPECT_FALSE(pw.metadata("no such key").has_value());
  const ParquetFile hy(file("hy_gzip_dict.parquet"));
  EXPECT_EQ(hy.metadata("huggingface"), truth_["files"]["hy_gzip_dict.parquet"]["metadata"]["huggingface"]);
  EXPECT_FALSE(hy.metadata("ARROW:schema").has_value());
}

TEST_F(ParquetFixtures, AnUnknownColumnOrGroupIsNamed) {
  const std::string path = file("pw_none_v2_dict.parquet");
  const ParquetFile f(path);
  try {
    f.read("observation.velocity");
    FAIL() << "no error";
  } catch (const InputError& e) {
    expectOneLine(e.what(), path);
    EXPECT_NE(std::string(e.what()).find("no column observation.velocity; the columns are observation.state, action"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(f.integerRange("observation.velocity", 0).has_value());  // no column, no statistics
  EXPECT_FALSE(f.integerRange("index", 99).has_value());
  try {
    f.read("index", {0, 99});
    FAIL() << "no error";
  } catch (const InputError& e) {
    expectOneLine(e.what(), path);
    EXPECT_NE(std::string(e.what()).find("no row group 99; the file has 6"), std::string::npos) << e.what();
  }
}

TEST_F(ParquetFixtures, RefusedEncodingsAreNamedOnTheirColumnOnly) {
  std::size_t files = 0;
  for (const auto& [name, t] : truth_["files"].items()) {
    if (!t.contains("refused")) continue;
    ++files;
    SCOPED_TRACE(name);
    const std::string path = file(name);
    const ParquetFile f(path);
    const std::string column = t["refused"]["column"], encoding = t["refused"]["encoding"];
    try {
      f.read(column);
      FAIL() << "no error";
    } catch (const InputError& e) {
      const std::string m = e.what();
      expectOneLine(m, path);
      EXPECT_EQ(m.rfind(path + ": row group 0, column " + column + ", page at byte ", 0), 0u) << m;
      EXPECT_NE(m.find("the page's encoding " + encoding + " is not read by this reader"), std::string::npos) << m;
    }
    for (const std::string& c : t["columns"].get<std::vector<std::string>>())
      if (c != column) expectColumn(f.read(c), c, allRows());
  }
  EXPECT_EQ(files, 3u);
}

// INT96 and lists of lists are refused when their column is read, by name; the file opens and its
// other columns read (a LeRobot v3.0 episode table holds image statistics as lists of lists).
TEST_F(ParquetFixtures, RefusedLayoutsAreNamedWhenTheirColumnIsRead) {
  for (const auto& [name, column, what] :
       {std::tuple<std::string, std::string, std::string>{"hy_refused_int96.parquet", "index",
                                                          "column index is INT96 (a legacy timestamp)"},
        {"hy_refused_list_of_lists.parquet", "nested", "column nested is a list of lists (2 repetition levels)"}}) {
    SCOPED_TRACE(name);
    const ParquetFile f(file(name));
    ASSERT_TRUE(f.hasColumn(column));
    try {
      f.read(column);
      FAIL() << "no error";
    } catch (const InputError& e) {
      expectOneLine(e.what(), file(name));
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
    std::size_t others = 0;
    for (const std::string& c : f.columns())
      if (c != column) {
        EXPECT_EQ(f.read(c).rows(), static_cast<std::size_t>(f.rows())) << c;
        ++others;
      }
    EXPECT_GT(others, 0u);
  }
}

// `bytes` written to the scratch folder as `name`; its path.
std::string scratch(const std::string& name, const std::string& bytes) {
  return kccd::testing::writeScratch("test_parquet", name, bytes);
}

std::string openError(const std::string& path) {
  try {
    ParquetFile f(path);
  } catch (const InputError& e) {
    expectOneLine(e.what(), path);
    return e.what();
  }
  return "";
}

TEST_F(ParquetFixtures, WrongMagicEncryptionAndMissingFilesAreNamed) {
  const std::string bytes = readText(small("pw_snappy_v1_dict.parquet"));
  std::string b = bytes;
  b[0] = 'X';
  EXPECT_NE(openError(scratch("magic.parquet", b)).find("not a Parquet file (its first 4 bytes are not PAR1)"),
            std::string::npos);
  b = bytes;
  b[b.size() - 1] = 'E';
  EXPECT_NE(openError(scratch("pare.parquet", b)).find("an encrypted footer (PARE)"), std::string::npos);
  b = bytes;
  b[b.size() - 5] = '\x7f';  // the footer's length, past the file's start
  EXPECT_NE(openError(scratch("length.parquet", b)).find("the footer's length"), std::string::npos);
  EXPECT_NE(openError(scratch("empty.parquet", "")).find("fewer than the 12"), std::string::npos);
  EXPECT_NE(openError((dir_ / "missing.parquet").string()).find("cannot be opened"), std::string::npos);
}

TEST_F(ParquetFixtures, EveryCutOfASmallFileReadsOrThrowsInputError) {
  for (const char* name : {"pw_snappy_v1_dict.parquet", "hy_gzip_plain.parquet"}) {
    SCOPED_TRACE(name);
    const std::string bytes = readText(small(name));
    ASSERT_GT(bytes.size(), 500u);
    ASSERT_TRUE(readsWhole(small(name)));
    std::size_t threw = 0;
    for (std::size_t cut = 0; cut < bytes.size(); ++cut)
      threw += readsWhole(scratch("cut.parquet", bytes.substr(0, cut))) ? 0 : 1;
    EXPECT_EQ(threw, bytes.size());  // the footer is at the end: no cut leaves a file that reads
  }
}

TEST_F(ParquetFixtures, EveryFlippedByteReadsOrThrowsInputError) {
  for (const char* name : {"pw_zstd_v2_plain.parquet", "hy_none_dict.parquet"}) {
    SCOPED_TRACE(name);
    const std::string bytes = readText(small(name));
    ASSERT_TRUE(readsWhole(small(name)));
    std::size_t threw = 0, tries = 0;
    // Every byte inverted; the last KiB (the footer, where every length and offset is) also with
    // its lowest and highest bit flipped.
    for (const unsigned char flip : {0xffu, 0x01u, 0x80u}) {
      for (std::size_t at = flip == 0xff ? 0 : bytes.size() - std::min<std::size_t>(bytes.size(), 1024);
           at < bytes.size(); ++at) {
        std::string b = bytes;
        b[at] = static_cast<char>(static_cast<unsigned char>(b[at]) ^ flip);
        threw += readsWhole(scratch("flip.parquet", b)) ? 0 : 1;
        ++tries;
      }
    }
    // Damage in the footer and page headers is seen; in values it may read as other values.
    EXPECT_GT(threw, tries / 10) << threw << " of " << tries;
  }
}

// Damage only in the pages (the footer intact): each page's problem names its row group, column
// and byte.
TEST_F(ParquetFixtures, DamagedPagesNameTheirColumnAndByte) {
  const std::string path = small("pw_zstd_v2_plain.parquet");
  const std::string bytes = readText(path);
  std::size_t length = 0;
  for (int i = 0; i < 4; ++i)
    length |= static_cast<std::size_t>(static_cast<unsigned char>(bytes[bytes.size() - 8 + i])) << (8 * i);
  const std::size_t footer = bytes.size() - 8 - length;
  std::size_t page_errors = 0;
  for (std::size_t at = 4; at < footer; ++at) {
    std::string b = bytes;
    b[at] = static_cast<char>(~static_cast<unsigned char>(b[at]));
    const std::string p = scratch("page.parquet", b);
    const ParquetFile f(p);  // the footer is whole
    for (const std::string& c : f.columns()) {
      try {
        f.read(c);
      } catch (const InputError& e) {
        expectOneLine(e.what(), p);
        const std::string m = e.what();
        EXPECT_EQ(m.rfind(p + ": row group ", 0), 0u) << m;
        page_errors += m.find(", column " + c + ", page at byte ") != std::string::npos ? 1 : 0;
      }
    }
  }
  EXPECT_GT(page_errors, 50u);
}

// The Thrift compact protocol, written by hand for the files this test makes itself (fields in
// increasing order, at most 15 apart; lists of fewer than 15 elements).
class Compact {
 public:
  void i32(int id, std::int64_t v) { head(id, 5), zigzag(v); }
  void i64(int id, std::int64_t v) { head(id, 6), zigzag(v); }
  void boolean(int id, bool v) { head(id, v ? 1 : 2); }
  void string(int id, const std::string& v) { head(id, 8), varint(v.size()), bytes_ += v; }
  void beginStruct(int id) { head(id, 12), last_.push_back(0); }
  void beginList(int id, int type, int size) { head(id, 9), bytes_ += static_cast<char>(size << 4 | type); }
  void listString(const std::string& v) { varint(v.size()), bytes_ += v; }
  void listI32(std::int64_t v) { zigzag(v); }
  void beginListStruct() { last_.push_back(0); }
  void end() { bytes_ += '\0', last_.pop_back(); }
  const std::string& bytes() const { return bytes_; }

 private:
  void head(int id, int type) {
    bytes_ += static_cast<char>((id - last_.back()) << 4 | type);
    last_.back() = id;
  }
  void varint(std::uint64_t v) {
    for (; v >= 0x80; v >>= 7) bytes_ += static_cast<char>(v | 0x80);
    bytes_ += static_cast<char>(v);
  }
  void zigzag(std::int64_t v) { varint((static_cast<std::uint64_t>(v) << 1) ^ static_cast<std::uint64_t>(v >> 63)); }
  std::string bytes_;
  std::vector<int> last_{0};
};

std::string le32(std::uint32_t v) {
  return {static_cast<char>(v), static_cast<char>(v >> 8), static_cast<char>(v >> 16), static_cast<char>(v >> 24)};
}

// A file of one required BYTE_ARRAY column "s" in one row group of `rows` rows: a dictionary page
// of one `entry`, then one v2 data page whose dictionary indices are a single run of `rows` zeros
// (bit width 0). Few bytes that expand to rows times the entry.
std::string dictionaryRunFile(std::int64_t rows, const std::string& entry) {
  const std::string dict_body = le32(static_cast<std::uint32_t>(entry.size())) + entry;
  Compact dict;
  dict.i32(1, 2);  // DICTIONARY_PAGE
  dict.i32(2, static_cast<std::int64_t>(dict_body.size()));
  dict.i32(3, static_cast<std::int64_t>(dict_body.size()));
  dict.beginStruct(7);
  dict.i32(1, 1);
  dict.i32(2, 0);  // PLAIN
  dict.end();
  dict.end();
  std::string data_body(1, '\0');  // bit width 0, then the run's header: rows << 1
  for (std::uint64_t v = static_cast<std::uint64_t>(rows) << 1; v > 0 || data_body.size() == 1; v >>= 7)
    data_body += static_cast<char>((v & 0x7f) | (v >= 0x80 ? 0x80 : 0));
  Compact data;
  data.i32(1, 3);  // DATA_PAGE_V2
  data.i32(2, static_cast<std::int64_t>(data_body.size()));
  data.i32(3, static_cast<std::int64_t>(data_body.size()));
  data.beginStruct(8);
  data.i32(1, rows);
  data.i32(2, 0);
  data.i32(3, rows);
  data.i32(4, 8);  // RLE_DICTIONARY
  data.i32(5, 0);
  data.i32(6, 0);
  data.boolean(7, false);
  data.end();
  data.end();
  const std::string pages = dict.bytes() + dict_body + data.bytes() + data_body;
  const std::int64_t data_at = 4 + static_cast<std::int64_t>(dict.bytes().size() + dict_body.size());
  Compact f;
  f.i32(1, 2);
  f.beginList(2, 12, 2);
  f.beginListStruct();
  f.string(4, "schema");
  f.i32(5, 1);
  f.end();
  f.beginListStruct();
  f.i32(1, 6);  // BYTE_ARRAY
  f.i32(3, 0);  // REQUIRED
  f.string(4, "s");
  f.end();
  f.i64(3, rows);
  f.beginList(4, 12, 1);
  f.beginListStruct();
  f.beginList(1, 12, 1);
  f.beginListStruct();
  f.i64(2, 4);
  f.beginStruct(3);
  f.i32(1, 6);
  f.beginList(2, 5, 2);
  f.listI32(0);
  f.listI32(8);
  f.beginList(3, 8, 1);
  f.listString("s");
  f.i32(4, 0);  // UNCOMPRESSED
  f.i64(5, rows);
  f.i64(6, static_cast<std::int64_t>(pages.size()));
  f.i64(7, static_cast<std::int64_t>(pages.size()));
  f.i64(9, data_at);
  f.i64(11, 4);
  f.end();
  f.end();
  f.i64(2, static_cast<std::int64_t>(pages.size()));
  f.i64(3, rows);
  f.end();
  f.end();
  return "PAR1" + pages + f.bytes() + le32(static_cast<std::uint32_t>(f.bytes().size())) + "PAR1";
}

TEST(ParquetBombs, AFileMadeByHandReads) {
  const std::string path = scratch("dictionary_run.parquet", dictionaryRunFile(1000, "x"));
  const ParquetFile f(path);
  EXPECT_EQ(f.columns(), std::vector<std::string>{"s"});
  const ParquetColumn c = f.read("s");
  ASSERT_EQ(c.rows(), 1000u);
  EXPECT_EQ(c.bytes, std::vector<std::string>(1000, "x"));
}

TEST(ParquetBombs, RunsThatExpandPastTheBudgetAreRefused) {
  // 2^30 values: 16 GiB of results from 60 bytes, refused before anything is allocated for them.
  // A million copies of a 4 KiB dictionary entry: 4 GiB of strings.
  for (const auto& [rows, entry] :
       {std::pair<std::int64_t, std::string>{std::int64_t{1} << 30, "x"}, {1000000, std::string(4096, 'x')}}) {
    const std::string path = scratch("bomb.parquet", dictionaryRunFile(rows, entry));
    const ParquetFile f(path);
    try {
      f.read("s");
      FAIL() << "no error for " << rows << " rows";
    } catch (const InputError& e) {
      expectOneLine(e.what(), path);
      EXPECT_EQ(std::string(e.what()).rfind(path + ": row group 0, column s, page at byte ", 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find("(a decompression bomb)"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
