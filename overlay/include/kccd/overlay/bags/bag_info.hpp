// What a robot log holds as JSON (`kccd bag info --json`, kccd.read_bag's "info").
#pragma once

#include <nlohmann/json.hpp>

#include "kccd/logs/bag_summary.hpp"

namespace kccd::overlay {

/// The summary as docs/formats.md's bag info JSON: the log's format, message count and times
/// (nanoseconds as decimal strings), chunks, damage, and per topic its type, count, times, rate,
/// header-stamp skews and where its definition came from.
nlohmann::json bagInfoJson(const logs::BagSummary& summary);

}  // namespace kccd::overlay
