#include "cli_util.hpp"

#include <cmath>
#include <sstream>

namespace kccd::cli {

std::vector<double> parseList(const std::string& text, const std::string& option) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  int index = 0;
  while (std::getline(ss, item, ',')) {
    std::size_t used = 0;
    double v = 0.0;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    while (used < item.size() && std::isspace(static_cast<unsigned char>(item[used]))) ++used;
    if (used == 0 || used != item.size())
      throw UsageError(option + ": value " + std::to_string(index + 1) + " ('" + item + "') is not a number");
    out.push_back(v);
    ++index;
  }
  if (!text.empty() && text.back() == ',') throw UsageError(option + ": trailing comma");
  return out;
}

nlohmann::json number(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr); }

nlohmann::json vec3(const Vec3& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

Model loadOrExplain(const std::string& path) {
  try {
    return loadModel(path);
  } catch (const ModelError& e) {
    throw UsageError(e.what());
  }
}

}  // namespace kccd::cli
