// bench_trade's command line: what to measure, how often, and where the tables go.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "kccd/query.hpp"

namespace kccd::bench {

/// Which search finds each pair's closest configuration: this program's own, the library's, or both.
enum class Oracle { Own, Library, Both };

/// The --exact margin setting (resolved to each model's margin).
inline constexpr double kExactAtMargin = -2.0;

/// bench_trade's options (see its --help).
struct Options {
  int boxes = 256;  ///< per box set
  std::vector<int> budgets{4, 8, 12, 16, 24, 32, 48, 64};
  std::vector<std::string> scenes{"humanoid", "industrial_cell"};
  int repeats = 3;
  std::uint64_t seed = 1;
  int search_effort = 1;  ///< multiplies the own search's samples, starts and steps
  Oracle oracle = Oracle::Both;
  /// QueryOptions::exact_below of the measured queries: -1 the library's default (the margin for
  /// collision queries, the margin plus QueryOptions::exact_band for distance queries);
  /// kExactAtMargin the model's margin; +inf every pair; -inf off; else metres.
  double exact_below = -1.0;
  int splits = kccd::QueryOptions{}.exact_splits;           ///< QueryOptions::exact_splits of the measured queries
  double split_gap = kccd::QueryOptions{}.exact_split_gap;  ///< QueryOptions::exact_split_gap of the measured queries
  std::string markdown, csv, plot;
};

/// The options of a command line; prints --help and exits 0, or exits 2 with one line naming a bad option.
Options parseOptions(int argc, char** argv);

}  // namespace kccd::bench
