// Reading Parquet files (https://parquet.apache.org/docs/file-format/) as written by Arrow's writers
// (pyarrow, arrow-rs) and hyparquet-writer for robot-learning datasets: the footer (Thrift compact
// protocol), PLAIN, dictionary (PLAIN_DICTIONARY, RLE_DICTIONARY) and RLE (booleans) encodings,
// RLE/bit-packed levels, one level of lists (Arrow's three-level LIST, fixed-size lists, legacy
// two-level repeated fields), structs, int32/int64/float/double/boolean/byte-array/string leaves,
// data pages v1 and v2, and snappy, zstd, gzip or no compression. Anything else (another encoding,
// a list of lists, INT96, LZ4, BROTLI, encryption) is refused by name in one line: a column's
// layout when that column is read (the file's other columns still read). Only the row groups and
// columns asked for are read from disk.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace kccd::logs {

/// One leaf column read for a run of rows. Row r's values are `numbers` (a numeric leaf) or
/// `bytes` (a byte-array leaf) in [rowStart[r], rowStart[r+1]): one value for a plain column, a
/// list's elements for a list column (none for an empty or null list). A null value is NaN in
/// `numbers` and an empty string in `bytes`.
struct ParquetColumn {
  std::string name;                   ///< the column's path, its names joined by '/' (see ParquetFile::columns)
  bool isBytes = false;               ///< byte-array leaf (binary, string): values in `bytes`, else in `numbers`
  bool isList = false;                ///< the leaf sits inside a list: rows hold any number of values
  std::vector<double> numbers;        ///< int32, int64 (exact up to 2^53), float, double, boolean (0/1)
  std::vector<std::string> bytes;     ///< binary and string values
  std::vector<std::size_t> rowStart;  ///< rows + 1 offsets into `numbers` or `bytes`

  std::size_t rows() const { return rowStart.empty() ? 0 : rowStart.size() - 1; }
};

/// A row group: its rows and where they start in the file's row order.
struct ParquetRowGroup {
  std::int64_t rows = 0;
  std::int64_t firstRow = 0;
};

/// A Parquet file's footer, and its columns read on demand. Every length and offset in the file is
/// checked against the file's size before anything is allocated for it; decompressed pages are
/// held to the size their headers declare.
class ParquetFile {
 public:
  /// Opens `path` and reads its footer; throws InputError ("FILE: problem") when the file is not
  /// Parquet, is cut short, or its schema is malformed (a column of a layout this reader refuses,
  /// INT96 or a list of lists, is refused when read).
  explicit ParquetFile(const std::string& path);
  ~ParquetFile();
  ParquetFile(ParquetFile&&) noexcept;
  ParquetFile& operator=(ParquetFile&&) noexcept;

  /// The file's name as messages show it.
  const std::string& path() const;
  /// Rows in the whole file.
  std::int64_t rows() const;
  const std::vector<ParquetRowGroup>& rowGroups() const;
  /// The leaf columns' names: the schema's field names from the root down, joined by '/', with a
  /// list's inner levels left out ("observation.state" for Arrow's list<float> field
  /// `observation.state/list/element`; "observation.images.top/bytes" for a struct's field).
  std::vector<std::string> columns() const;
  /// True when `name` is one of columns().
  bool hasColumn(const std::string& name) const;
  /// The key-value metadata of the footer (e.g. "huggingface", "ARROW:schema").
  std::optional<std::string> metadata(const std::string& key) const;
  /// The min and max statistics of an integer column in row group `group`, where the writer
  /// recorded them (none for a column or a row group the file does not have).
  std::optional<std::pair<std::int64_t, std::int64_t>> integerRange(const std::string& name, std::size_t group) const;

  /// Reads column `name` over the row groups `groups` (every group when empty), in the order
  /// given. Throws InputError ("FILE: row group G, column NAME, page at byte B: problem") on a page
  /// that is corrupt, cut short, or uses an encoding or compression this reader refuses, and on a
  /// name that is not a column ("no column NAME; the columns are ...").
  ParquetColumn read(const std::string& name, const std::vector<std::size_t>& groups = {}) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace kccd::logs
