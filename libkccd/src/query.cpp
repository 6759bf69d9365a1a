// Names of the query value types (kccd/query.hpp).
#include "kccd/query.hpp"

#include <limits>

namespace kccd {

const char* toString(Status status) {
  switch (status) {
    case Status::Ok:
      return "ok";
    case Status::WrongStateSize:
      return "wrong_state_size";
    case Status::NonFiniteState:
      return "non_finite_state";
    case Status::LowerAboveUpper:
      return "lower_above_upper";
    case Status::ExactNeedsPoint:
      return "exact_needs_point_interval";
    case Status::NumericalFailure:
      return "numerical_failure";
  }
  return "?";
}

const char* toString(QueryType type) {
  switch (type) {
    case QueryType::Collision:
      return "collision";
    case QueryType::Closest:
      return "closest";
    case QueryType::NClosest:
      return "nclosest";
    case QueryType::Distances:
      return "distances";
  }
  return "?";
}

std::optional<QueryType> queryTypeFromString(std::string_view name) {
  for (const QueryType t : {QueryType::Collision, QueryType::Closest, QueryType::NClosest, QueryType::Distances})
    if (name == toString(t)) return t;
  return std::nullopt;
}

std::optional<double> exactBelowFromWord(std::string_view word, double margin) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (word == "band") return -1.0;
  if (word == "margin") return margin;
  if (word == "all") return kInf;
  if (word == "off") return -kInf;
  return std::nullopt;
}

}  // namespace kccd
