// What the robot-log fuzz targets share: a log summarised as `kccd bag info` does, its summary
// consistent with itself, or one InputError line naming the file.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <string>

#include "fuzz_support.hpp"
#include "kccd/input_error.hpp"
#include "kccd/logs/bag_summary.hpp"

namespace kccd::fuzz {

/// Summarises the log at `path`; aborts (a finding) on a summary whose counts and times disagree
/// (a topic's, or its publishers' with it), or on an error that breaks the one-line contract.
inline void summarizeOrExplain(const std::string& path) {
  try {
    const kccd::logs::BagSummary b = kccd::logs::summarizeBag(path);
    std::uint64_t n = 0;
    for (const auto& t : b.topics) {
      n += t.count;
      if (t.count == 0 || t.first_log_time > t.last_log_time || t.stamped > t.count || t.zero_stamps > t.stamped)
        std::abort();
      // A topic's row sums its publishers' rows.
      std::uint64_t published = 0;
      for (const auto& p : t.publishers) published += p.count;
      if (t.publishers.empty() || published != t.count) std::abort();
    }
    if (n != b.messages) std::abort();
  } catch (const kccd::InputError& e) {
    checkMessage(e.what(), path);
  }
}

}  // namespace kccd::fuzz
