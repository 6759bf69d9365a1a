// The safety vocabulary (kccd/safety_status.hpp).
#include "kccd/safety_status.hpp"

namespace kccd {

const char* toString(SafetyStatus status) {
  switch (status) {
    case SafetyStatus::Clear:
      return "clear";
    case SafetyStatus::WithinMargin:
      return "within_margin";
    case SafetyStatus::Colliding:
      return "colliding";
    case SafetyStatus::NoState:
      return "no_state";
  }
  return "?";
}

SafetyStatus safetyStatus(double min_distance, double margin) {
  if (!(min_distance > 0.0)) return SafetyStatus::Colliding;  // also NaN
  return min_distance <= margin ? SafetyStatus::WithinMargin : SafetyStatus::Clear;
}

SafetyStatus safetyStatus(const QueryResult& result) {
  if (result.status != Status::Ok) return SafetyStatus::Colliding;
  return safetyStatus(result.min_distance, result.margin);
}

}  // namespace kccd
