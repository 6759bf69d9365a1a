// Command-line arguments of the kccd subcommands: the option error, validators and readable
// parser messages, number lists and interval boxes.
#pragma once

#include <map>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "kccd/braking.hpp"

#include "kccd/input_error.hpp"
#include "kccd/model.hpp"

namespace kccd::cli {

/// A bad option or argument: printed as one line, exit status BadInput (an InputError like the
/// readers' errors, so main maps them in one place).
class UsageError : public InputError {
 public:
  using InputError::InputError;
};

/// A command-line parser message made readable: one line, huge bounds (DBL_MAX) written short.
std::string optionMessage(const std::string& text);

/// An option validator: a finite number in [lo, hi] (NaN and infinities are refused).
CLI::Validator finiteIn(double lo, double hi);

/// A seed: a whole number 0 ... 2^64 - 1 (a negative one is refused, never wrapped).
CLI::Validator seedNumber();

/// Parses "a,b,c" into numbers; `option` names the flag in error messages.
std::vector<double> parseList(const std::string& text, const std::string& option);

/// "a,b,c" split at every comma ("" gives no item, "a," gives "a" and ""): column lists.
std::vector<std::string> splitCommas(const std::string& text);

/// The interval box from `--state` (a single configuration) or `--lower`/`--upper`, each checked
/// against the model's state size; `missing` is the message when neither is complete. With
/// `finite`, NaN and infinite values are rejected too (else they reach the query as a status).
struct StateBox {
  std::vector<double> lower, upper;
  bool point = false;  ///< given with --state
};
StateBox parseStateBox(const Model& m, const std::string& state, const std::string& lower, const std::string& upper,
                       const std::string& missing, bool finite);

/// Called in a catch block with the library's error `e`: when it is about a field of a request
/// ("fps: ...": a field, no source), a UsageError with the field as this command line spells it
/// (`spelling[field]`, else --field with dashes for underscores); otherwise the error rethrown.
/// A request field as the command line spells it: "--" and the field with '-' for '_' (after its
/// last '.': "braking.latency" is --latency), unless `spelling` names it otherwise ("output": "-o").
std::string optionSpelling(const std::string& field, const std::map<std::string, std::string>& spelling = {});
[[noreturn]] void rethrowAsOption(const InputError& e, const std::map<std::string, std::string>& spelling = {});

/// Adds the braking options (--latency, --deceleration, --max-acceleration, --position-error,
/// --velocity-error: every joint's, with --swept) into `braking` (kccd overlay and kccd check).
void addBrakingOptions(CLI::App& sub, BrakingParams& braking);
/// True when any braking option was given on the command line.
bool brakingGiven(const CLI::App& sub);

/// Adds `--lerobot DIR`, `--episode N`, `--state-key KEY` and, when `frame_by` is given,
/// `--frame-by auto|timestamp|index` (kccd overlay and kccd check: a LeRobot dataset's episode).
void addLerobotOptions(CLI::App& sub, std::string& dataset, long& episode, std::string& state_key,
                       std::string* frame_by = nullptr);

}  // namespace kccd::cli
