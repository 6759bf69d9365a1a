// Helpers shared by the kccd subcommands: one-line errors, number lists, JSON conversions.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "kccd/model.hpp"

namespace kccd::cli {

/// A user error: printed as one line, exit code 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Parses "a,b,c" into numbers; `option` names the flag in error messages.
std::vector<double> parseList(const std::string& text, const std::string& option);

/// A non-finite value as JSON null, otherwise the number.
nlohmann::json number(double value);
nlohmann::json vec3(const Vec3& v);

/// Loads a model, turning every failure into one line on stderr (throws UsageError).
Model loadOrExplain(const std::string& path);

}  // namespace kccd::cli
