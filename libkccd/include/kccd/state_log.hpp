// State logs (docs/formats.md section 6): a CSV of a robot's state over time, read against a
// model, and the state at any time (a sample, an interpolation between two samples, or none).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "kccd/input_error.hpp"
#include "kccd/model.hpp"

namespace kccd {

/// A state log that cannot be used. One line: "file:line:col: column 'name': problem", without
/// the column number (or name) where none applies, and "file: problem" for the file itself.
/// `col` is the 1-based byte position in the line (a UTF-8 BOM is not counted).
class StateLogError : public InputError {
 public:
  using InputError::InputError;
};

/// Largest state log file loadStateLog() reads. The parsed log takes at most about 4 bytes per
/// byte of text (8 per number, at least 2 bytes of text per number), 8 with velocity columns.
inline constexpr std::size_t kMaxStateLogBytes = std::size_t{1} << 30;
/// Largest magnitude of any number in a log (times and values): differences stay finite.
inline constexpr double kMaxStateLogMagnitude = 1e300;
/// A query time within this many seconds of a sample time is that sample (StateMatch::Exact).
inline constexpr double kStateTimeTolerance = 1e-9;

/// A parsed log: samples in time order, values in the model's state order.
struct StateLog {
  std::vector<std::string> names;             ///< model.stateNames() at parse time
  std::vector<std::uint8_t> circular;         ///< per value: 1 for a revolute joint without limits (unwrapped)
  std::vector<std::uint8_t> logged_velocity;  ///< per value: 1 when the log has its NAME.vel column
  std::vector<double> times;                  ///< seconds, strictly increasing, at least one
  std::vector<double> values;                 ///< times.size() x names.size(), row-major
  std::vector<double> velocities;             ///< same shape when any NAME.vel column was read (NaN where a
                                              ///< value has none), otherwise empty
  std::vector<std::string> ignored;           ///< the header's ignored columns, in file order

  std::size_t rows() const { return times.size(); }
  std::size_t stateSize() const { return names.size(); }
  /// True when at least one NAME.vel column was read.
  bool hasVelocities() const { return !velocities.empty(); }
  /// The values of sample `i`.
  std::span<const double> row(std::size_t i) const { return {values.data() + i * names.size(), names.size()}; }
  /// The median time between consecutive samples (0 with a single sample).
  double medianPeriod() const;
};

/// Parses the CSV `text` against `model`; `source` names it in messages. Dialect: comma-separated,
/// the first line the header, LF or CRLF line ends, an optional UTF-8 BOM, no quoting (a '"' is an
/// error), no comment lines, no empty line (except one at the very end), no padding around names
/// or numbers. Header: `time`, one column per model state value (model.stateNames()) and optional
/// `NAME.vel` velocity columns, in any order, none named twice. A column in `ignore_columns` is
/// skipped unparsed (its fields may hold any text without ',' or '"'); this applies to unknown and
/// `NAME.vel` columns, while `time` and the state values are required, so listing one of them is an
/// error. Any other column is an error. Rows: as many fields as the header; numbers C-locale
/// decimals (`-12.5`, `.5`, `1e-3`; no '+' sign, hex, inf or nan), magnitude at most
/// kMaxStateLogMagnitude; time strictly increasing; at least one row. Throws StateLogError.
StateLog parseStateLog(std::string_view text, const std::string& source, const Model& model,
                       std::span<const std::string> ignore_columns = {});
/// Reads a regular file of at most kMaxStateLogBytes (a FIFO or device is refused without blocking)
/// and parses it; the path names it in messages. Throws StateLogError.
StateLog loadStateLog(const std::string& path, const Model& model, std::span<const std::string> ignore_columns = {});

/// How stateAt() found a state.
enum class StateMatch : std::uint8_t {
  Exact,         ///< a sample within kStateTimeTolerance of the time
  Interpolated,  ///< between two consecutive samples at most max_gap apart
  None           ///< no state: outside the log, in a longer gap, or a velocity the log cannot give
};

const char* toString(StateMatch match);

/// The state at `time` (seconds, log time). Exact: the nearest sample within kStateTimeTolerance.
/// Otherwise, strictly between samples i and i+1 with t[i+1] - t[i] <= max_gap: linear
/// interpolation, except that values of revolute joints without limits follow the shorter arc
/// (3.1 -> -3.1 passes through pi, not 0; the result is near the nearer sample's value, not
/// wrapped into [-pi, pi]). Before the first or after the last sample (beyond the tolerance), or
/// in a longer gap: None, nothing is extrapolated. A non-finite time is None.
/// `velocity`, when not empty, gets the rates: a logged NAME.vel column is taken at a sample and
/// interpolated linearly between samples; a value without one gets the slope of the bracketing
/// samples (shorter arc when unwrapped), at an exact sample the central difference of its
/// neighbours within max_gap (one-sided when only one is), and None when the sample has no
/// neighbour within max_gap. Such a slope can be +-infinity for absurd logs (jumps near 1e300
/// within a subnormal time step); treat a non-finite velocity as unsafe.
/// `state` must have log.stateSize() values and `velocity` that many or none
/// (std::invalid_argument otherwise). On None both are left unchanged. Allocates nothing when
/// the sizes are right (a binary search over the times).
StateMatch stateAt(const StateLog& log, double time, double max_gap, std::span<double> state,
                   std::span<double> velocity = {});

}  // namespace kccd
