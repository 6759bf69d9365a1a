// What the kccd subcommands print: one-line messages, numbers, JSON values (progress: cli_progress.hpp).
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "kccd/format_number.hpp"
#include "kccd/ssch.hpp"

namespace kccd::cli {

/// `text` as one printable line (control bytes escaped, line breaks as spaces), for messages.
std::string oneLine(const std::string& text);

/// A non-finite value as JSON null, otherwise the number.
nlohmann::json number(double value);
nlohmann::json vec3(const Vec3& v);

/// kccd::formatNumber under the name the commands knew it by (`digits` significant digits).
inline std::string format(double value, int digits = 10) { return formatNumber(value, digits); }

}  // namespace kccd::cli
