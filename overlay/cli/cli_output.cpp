#include "cli_output.hpp"

#include <cmath>

#include "kccd/input_error.hpp"

namespace kccd::cli {

std::string oneLine(const std::string& text) {
  std::string flat = text;
  for (char& c : flat)
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  while (!flat.empty() && flat.back() == ' ') flat.pop_back();
  return printable(flat, 400);
}

nlohmann::json number(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr); }

nlohmann::json vec3(const Vec3& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

}  // namespace kccd::cli
