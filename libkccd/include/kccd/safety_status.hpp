// The one safety vocabulary of reports, pictures and recordings: what a distance bound means.
#pragma once

#include <cstdint>

#include "kccd/query.hpp"

namespace kccd {

/// What a bound (or its absence) says about a robot, a body or a frame: clear, within the safety
/// margin, colliding (also every unsafe query status), or no state known to check.
enum class SafetyStatus : std::uint8_t { Clear, WithinMargin, Colliding, NoState };

/// "clear", "within_margin", "colliding", "no_state" (the words of the JSON reports).
const char* toString(SafetyStatus status);

/// The status of a lower bound `min_distance` against `margin`: <= 0 colliding, <= margin within
/// the margin, else clear; a NaN bound is colliding (nothing is known to be safe).
SafetyStatus safetyStatus(double min_distance, double margin);

/// The status of a query result: any status but Ok is colliding (unsafe, stop); otherwise that of
/// its smallest bound against its margin.
SafetyStatus safetyStatus(const QueryResult& result);

}  // namespace kccd
