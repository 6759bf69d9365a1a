// How a robot log's joint states become the model's state values when their names or units differ
// (`kccd overlay --bag ... --joint-map MAP.yaml`): per state value, the logged joint it is read
// from, a scale and an offset, or a constant. The format is docs/formats.md's "joint map".
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "kccd/model.hpp"
#include "kccd/state_log.hpp"

namespace kccd::overlay {

/// Where one state value of the model comes from.
struct JointSource {
  std::string state;   ///< the model's state value
  std::string from;    ///< the logged joint read (empty with a constant)
  double scale = 1.0;  ///< value = scale * logged + offset; velocity = scale * logged velocity (`degrees`,
                       ///< `range` set it)
  double offset = 0.0;
  std::optional<double> constant;  ///< a value the log does not give (velocity 0)
  int line = 0;                    ///< where the map gives it (0: not in the map, read by its own name)
};

/// Every state value of a model, in the model's order, with where it comes from.
struct JointMap {
  std::string source;               ///< the map file ("" when every value is read by its own name)
  std::vector<JointSource> states;  ///< one per state value of the model, in order
  /// The logged joints read, each once, in first-use order.
  std::vector<std::string> logged() const;
};

/// The identity map of `model`: each state value read from the logged joint of the same name.
JointMap identityJointMap(const Model& model);

/// Reads a joint map for `model` from `text` (`source` names it in messages). State values the
/// map does not list are read by their own name. Throws InputError "source:line:column: field:
/// problem" for a state value the model lacks, an entry giving both `from` and `constant`, a scale
/// of 0 or beyond 1e6, an offset beyond 1e6, an unknown key.
JointMap parseJointMap(const std::string& text, const std::string& source, const Model& model);

/// The state log of `model` from a log's rows of named values (a dataset's `observation.state`):
/// row i at `times[i]` holds `values[i * names.size() ...]`, one per name. Each state value is read
/// as `map` says (the identity map when it lists no state), its logged joint found by its name or
/// by NAME.pos (LeRobot's names). Throws InputError "SOURCE: ..." naming a state value the rows do
/// not give, with the names they have and `map_option` (how the front end names the joint map).
StateLog mappedStateLog(const JointMap& map, const Model& model, std::span<const std::string> names,
                        std::span<const double> times, std::span<const double> values, const std::string& source,
                        const std::string& map_option);

/// parseJointMap of the file at `path` (at most 1 MiB). Throws InputError or FileError.
JointMap loadJointMap(const std::string& path, const Model& model);

}  // namespace kccd::overlay
