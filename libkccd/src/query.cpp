// Names of the query value types (kccd/query.hpp).
#include "kccd/query.hpp"

namespace kccd {

const char* toString(Status status) {
  switch (status) {
    case Status::Ok: return "ok";
    case Status::WrongStateSize: return "wrong_state_size";
    case Status::NonFiniteState: return "non_finite_state";
    case Status::LowerAboveUpper: return "lower_above_upper";
    case Status::ExactNeedsPoint: return "exact_needs_point_interval";
    case Status::NumericalFailure: return "numerical_failure";
  }
  return "?";
}

const char* toString(QueryType type) {
  switch (type) {
    case QueryType::Collision: return "collision";
    case QueryType::Closest: return "closest";
    case QueryType::NClosest: return "nclosest";
    case QueryType::Distances: return "distances";
  }
  return "?";
}

}  // namespace kccd
