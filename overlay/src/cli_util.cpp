#include "cli_util.hpp"

#include <cmath>
#include <algorithm>
#include <cerrno>
#include <cstring>
#include <sstream>

#include "kccd/modelling/fit.hpp"

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

namespace {

std::vector<double> stateVector(const Model& m, const std::string& text, const std::string& option, bool finite) {
  std::vector<double> v = parseList(text, option);
  if (static_cast<int>(v.size()) != m.stateSize()) {
    std::string names;
    for (const std::string& n : m.stateNames()) names += (names.empty() ? "" : ", ") + n;
    throw UsageError(option + " has " + std::to_string(v.size()) + " values but model '" + m.name + "' has " +
                     std::to_string(m.stateSize()) + " state values (" + names + ")");
  }
  for (std::size_t i = 0; finite && i < v.size(); ++i)
    if (!std::isfinite(v[i]))
      throw UsageError(option + ": value " + std::to_string(i + 1) + " (" + m.stateNames()[i] + ") is not finite");
  return v;
}

}  // namespace

StateBox parseStateBox(const Model& m, const std::string& state, const std::string& lower, const std::string& upper,
                       const std::string& missing, bool finite) {
  StateBox box;
  if (!state.empty()) {
    if (!lower.empty() || !upper.empty()) throw UsageError("give either --state or --lower/--upper, not both");
    box.lower = box.upper = stateVector(m, state, "--state", finite);
    box.point = true;
    return box;
  }
  if (lower.empty() || upper.empty()) throw UsageError(missing);
  box.lower = stateVector(m, lower, "--lower", finite);
  box.upper = stateVector(m, upper, "--upper", finite);
  return box;
}

void checkCorePoints(int k) {
  if (k < 1 || k > modelling::kMaxCorePoints)
    throw UsageError("--points: the number of core points K must be 1 ... " +
                     std::to_string(modelling::kMaxCorePoints) + " (got " + std::to_string(k) + ")");
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

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <unistd.h>

namespace kccd::cli {
namespace {
double nowSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

Progress::Progress(std::string what, bool quiet)
    : what_(std::move(what)), quiet_(quiet), tty_(isatty(STDERR_FILENO) != 0), last_time_(nowSeconds()) {}

Progress::~Progress() { finish(); }

void Progress::update(double fraction) {
  if (quiet_ || finished_) return;
  fraction = std::clamp(fraction, 0.0, 1.0);
  const double t = nowSeconds();
  if (tty_) {
    if (fraction - last_ < 0.01 && fraction < 1.0) return;
    const int width = 30, filled = static_cast<int>(fraction * width);
    std::cerr << "\r" << what_ << " [" << std::string(filled, '#') << std::string(width - filled, ' ') << "] "
              << static_cast<int>(fraction * 100) << "%" << std::flush;
    shown_ = true;
  } else if (t - last_time_ >= 5.0) {
    std::cerr << what_ << ": " << static_cast<int>(fraction * 100) << "%\n";
    last_time_ = t;
  }
  last_ = fraction;
}

void Progress::finish() {
  if (finished_) return;
  finished_ = true;
  if (shown_) std::cerr << "\r" << std::string(what_.size() + 40, ' ') << "\r" << std::flush;
}

void writeFileAtomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".kccd-tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw UsageError(path + ": cannot write (" + std::strerror(errno) + ")");
    out << text;
    out.flush();
    if (!out) {
      std::remove(tmp.c_str());
      throw UsageError(path + ": write failed");
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    throw UsageError(path + ": cannot replace the file (" + ec.message() + ")");
  }
}

std::string format(double value, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, value);
  return buf;
}

void editFile(const std::string& path, const std::function<std::string(const std::string&)>& edit) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw UsageError(path + ": cannot read the file");
  std::stringstream text;
  text << in.rdbuf();
  std::string edited;
  try {
    edited = edit(text.str());
  } catch (const std::runtime_error& e) {
    throw UsageError(e.what());
  }
  writeFileAtomically(path, edited);
}

}  // namespace kccd::cli
