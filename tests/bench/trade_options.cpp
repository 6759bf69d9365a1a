#include "trade_options.hpp"

#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>

namespace kccd::bench {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

[[noreturn]] void usageError(const std::string& message) {
  std::fprintf(stderr, "bench_trade: %s\n", message.c_str());
  std::exit(2);
}

std::vector<std::string> splitList(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

long parseWhole(const std::string& option, const std::string& v, long lo, long hi) {
  char* end = nullptr;
  const long x = std::strtol(v.c_str(), &end, 10);
  if (v.empty() || *end != '\0' || x < lo || x > hi)
    usageError(option + ": expected a whole number from " + std::to_string(lo) + " to " + std::to_string(hi) +
               ", got '" + v + "'");
  return x;
}

}  // namespace

Options parseOptions(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help") {
      std::printf(
          "bench_trade [--n N] [--quick] [--budgets 4,8,...] [--scenes humanoid,industrial_cell]\n"
          "            [--repeats R] [--seed S] [--oracle own|library|both] [--search-effort K]\n"
          "            [--exact default|margin|all|off|METRES] [--splits N] [--split-gap METRES]\n"
          "            [--markdown F] [--csv F] [--plot F.png]\n");
      std::exit(0);
    }
    if (a == "--quick") {
      o.boxes = 6;
      o.budgets = {4, 12, 64};
      o.repeats = 1;
      continue;
    }
    if (i + 1 >= argc) usageError(a + ": unknown option or missing value (see --help)");
    const std::string v = argv[++i];
    if (a == "--n") {
      o.boxes = static_cast<int>(parseWhole(a, v, 1, 100000));
    } else if (a == "--budgets") {
      o.budgets.clear();
      for (const std::string& b : splitList(v)) o.budgets.push_back(static_cast<int>(parseWhole(a, b, 1, 4096)));
      if (o.budgets.empty()) usageError("--budgets: expected a comma-separated list");
    } else if (a == "--scenes") {
      o.scenes = splitList(v);
      if (o.scenes.empty()) usageError("--scenes: expected a comma-separated list");
    } else if (a == "--repeats") {
      o.repeats = static_cast<int>(parseWhole(a, v, 1, 1000));
    } else if (a == "--search-effort") {
      o.search_effort = static_cast<int>(parseWhole(a, v, 1, 64));
    } else if (a == "--seed") {
      o.seed = static_cast<std::uint64_t>(parseWhole(a, v, 0, 1L << 40));
    } else if (a == "--oracle") {
      if (v == "own")
        o.oracle = Oracle::Own;
      else if (v == "library")
        o.oracle = Oracle::Library;
      else if (v == "both")
        o.oracle = Oracle::Both;
      else {
        usageError("--oracle: expected own, library or both, got '" + v + "'");
      }
    } else if (a == "--exact") {
      if (v == "default")
        o.exact_below = -1.0;
      else if (v == "margin")
        o.exact_below = kExactAtMargin;
      else if (v == "all")
        o.exact_below = kInf;
      else if (v == "off")
        o.exact_below = -kInf;
      else {
        char* end = nullptr;
        const double x = std::strtod(v.c_str(), &end);
        if (v.empty() || *end != '\0' || !(x >= 0.0))
          usageError("--exact: expected default, margin, all, off or a distance in metres, got '" + v + "'");
        o.exact_below = x;
      }
    } else if (a == "--splits") {
      o.splits = static_cast<int>(parseWhole(a, v, 0, kccd::kMaxExactSplits));
    } else if (a == "--split-gap") {
      char* end = nullptr;
      const double x = std::strtod(v.c_str(), &end);
      if (v.empty() || *end != '\0' || !(x >= 0.0 && x <= 1e3))
        usageError("--split-gap: expected metres >= 0, got '" + v + "'");
      o.split_gap = x;
    } else if (a == "--markdown") {
      o.markdown = v;
    } else if (a == "--csv") {
      o.csv = v;
    } else if (a == "--plot") {
#ifndef KCCD_BENCH_WITH_OPENCV
      usageError("--plot: this build has no OpenCV");
#endif
      o.plot = v;
    } else {
      usageError(a + ": unknown option (see --help)");
    }
  }
  return o;
}

}  // namespace kccd::bench
