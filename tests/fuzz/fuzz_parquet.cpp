// libFuzzer target: Parquet files as kccd's dataset tools read them (kccd::logs::ParquetFile: the
// footer's Thrift, the schema's levels and names, every column's pages over every row group, their
// decompression, encodings and levels, and the integer statistics). Any input must read or be
// rejected with kccd::InputError naming the file on one line; a column whose counts disagree with
// the file's, any other exception, a crash, a hang or a sanitizer report is a finding. Seeds:
// tests/datasets/write_parquet.mjs's files at 4 rows (parquet-wasm and hyparquet-writer).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "fuzz_support.hpp"
#include "kccd/input_error.hpp"
#include "kccd/logs/parquet_reader.hpp"

namespace {

// Reads `name` over every row group and checks the column against the file's row counts.
void readColumn(const kccd::logs::ParquetFile& f, const std::string& name) {
  const kccd::logs::ParquetColumn c = f.read(name);
  if (static_cast<std::int64_t>(c.rows()) != f.rows() || c.rowStart.empty() || c.rowStart.front() != 0 ||
      c.rowStart.back() != (c.isBytes ? c.bytes.size() : c.numbers.size()))
    std::abort();
  for (std::size_t r = 0; r + 1 < c.rowStart.size(); ++r)
    if (c.rowStart[r] > c.rowStart[r + 1] || (!c.isList && c.rowStart[r + 1] - c.rowStart[r] != 1)) std::abort();
  for (std::size_t g = 0; g < f.rowGroups().size(); ++g) {
    const auto range = f.integerRange(name, g);
    if (range && range->first > range->second) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = kccd::fuzz::writeInput("fuzz_parquet", "table.parquet", data, size);
  try {
    const kccd::logs::ParquetFile f(path);
    std::int64_t rows = 0;
    for (const auto& g : f.rowGroups()) {
      if (g.firstRow != rows || g.rows < 0) std::abort();
      rows += g.rows;
    }
    if (rows != f.rows()) std::abort();
    for (const std::string& name : f.columns()) {
      if (!f.hasColumn(name)) std::abort();
      try {
        readColumn(f, name);
      } catch (const kccd::InputError& e) {
        kccd::fuzz::checkMessage(e.what(), path);
      }
    }
  } catch (const kccd::InputError& e) {
    kccd::fuzz::checkMessage(e.what(), path);
  }
  return 0;
}
