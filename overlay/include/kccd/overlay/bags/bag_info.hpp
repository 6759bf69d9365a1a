// What a robot log holds as JSON (`kccd bag info --json`, kccd.read_bag's "info").
#pragma once

#include <nlohmann/json.hpp>

#include "kccd/logs/bag_summary.hpp"

namespace kccd::overlay {

/// The summary as docs/formats.md's bag info JSON: the log's format, message count and times
/// (nanoseconds as decimal strings), chunks, damage, and per topic its type, count, times, rate,
/// header-stamp skews, where its definition came from and its publishers (each with the same
/// figures for its own messages and its channel's metadata, e.g. a ROS 1 connection's callerid).
nlohmann::json bagInfoJson(const logs::BagSummary& summary);

}  // namespace kccd::overlay
