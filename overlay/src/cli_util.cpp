#include "cli_util.hpp"

#include <cmath>
#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <regex>
#include <sstream>

#include "kccd/modelling/fit.hpp"

namespace kccd::cli {

std::string oneLine(const std::string& text) {
  std::string flat = text;
  for (char& c : flat)
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  while (!flat.empty() && flat.back() == ' ') flat.pop_back();
  return printable(flat, 400);
}

std::string optionMessage(const std::string& text) {
  // CLI11 writes bounds such as DBL_MAX with every digit: shorten long numbers.
  static const std::regex long_number("[-+]?[0-9]{16,}(\\.[0-9]*)?(e[-+]?[0-9]+)?");
  std::string out;
  auto it = std::sregex_iterator(text.begin(), text.end(), long_number);
  std::size_t last = 0;
  for (; it != std::sregex_iterator(); ++it) {
    out += text.substr(last, it->position() - last);
    out += format(std::strtod(it->str().c_str(), nullptr), 6);
    last = it->position() + it->length();
  }
  out += text.substr(last);
  // CLI11's phrasing, said plainly.
  static const std::pair<std::regex, const char*> plain[] = {
      {std::regex("^(\\S+): [0-9]+ required \\S+ missing$"), "$1: needs a value"},
      {std::regex("^The following arguments? (was|were) not expected: (.*)$"), "unknown option or extra argument: $2"},
      {std::regex("^--([A-Za-z-]+): Value (.*) not in range (.*) to (.*)$"), "--$1: expected a whole number from $3 to $4, got '$2'"},
      {std::regex("^(.*) is required$"), "$1 is required"},
  };
  for (const auto& [pattern, replacement] : plain)
    if (std::regex_match(out, pattern)) {
      out = std::regex_replace(out, pattern, replacement);
      break;
    }
  return oneLine(out);
}

CLI::Validator finiteIn(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        const char* begin = text.c_str();
        char* end = nullptr;
        const double v = std::strtod(begin, &end);
        if (text.empty() || end != begin + text.size()) return "'" + printable(text, 40) + "' is not a number";
        if (!std::isfinite(v)) return "must be a finite number, got '" + printable(text, 40) + "'";
        if (v < lo || v > hi) return "must be in [" + format(lo, 6) + ", " + format(hi, 6) + "], got " + format(v, 6);
        return std::string();
      },
      "NUMBER in [" + format(lo, 6) + ", " + format(hi, 6) + "]");
}

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
      throw UsageError(option + ": value " + std::to_string(index + 1) + " ('" + printable(item, 40) + "') is not a number");
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
  if (m.stateSize() == 0 && lower.empty() && upper.empty()) {  // only fixed joints: one configuration
    if (!state.empty()) stateVector(m, state, "--state", finite);  // explains a value given anyway
    box.point = true;
    return box;
  }
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

Model loadOrExplain(const std::string& path, std::string* text) {
  try {
    if (text == nullptr) return loadModel(path);
    *text = readModelText(path);
    return parseModel(*text, path);
  } catch (const InputError& e) {
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

namespace {

// Where a write to `path` must land: the final target of a chain of symbolic links (so a link
// stays a link), or `path` itself.
std::filesystem::path writeTarget(const std::string& path) {
  std::error_code ec;
  std::filesystem::path p = path;
  for (int hops = 0; hops < 40 && std::filesystem::is_symlink(p, ec); ++hops) {
    const std::filesystem::path link = std::filesystem::read_symlink(p, ec);
    if (ec) break;
    p = link.is_absolute() ? link : p.parent_path() / link;
  }
  return p;
}

// Writes `text` to a new unique file beside `target` with `mode`, then renames it over `target`.
void replaceFile(const std::filesystem::path& target, const std::string& shown, const std::string& text, mode_t mode) {
  const std::filesystem::path dir = target.parent_path().empty() ? std::filesystem::path(".") : target.parent_path();
  std::string tmp = (dir / ("." + target.filename().string() + ".kccd-XXXXXX")).string();
  const int fd = mkstemp(tmp.data());
  if (fd < 0) throw UsageError(shown + ": cannot write (" + std::strerror(errno) + ")");
  bool ok = fchmod(fd, mode) == 0;
  std::size_t done = 0;
  while (ok && done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    ok = n > 0;
    if (ok) done += static_cast<std::size_t>(n);
  }
  const int err = ok ? 0 : errno;
  ok = ok && fsync(fd) == 0;
  ok = (::close(fd) == 0) && ok;
  if (!ok) {
    std::remove(tmp.c_str());
    throw UsageError(shown + ": write failed (" + std::strerror(err != 0 ? err : errno) + ")");
  }
  if (std::rename(tmp.c_str(), target.c_str()) != 0) {
    const int e = errno;
    std::remove(tmp.c_str());
    throw UsageError(shown + ": cannot replace the file (" + std::strerror(e) + ")");
  }
}

mode_t newFileMode() {
  const mode_t mask = umask(0);
  umask(mask);
  return 0666 & ~mask;
}

}  // namespace

void writeFileAtomically(const std::string& path, const std::string& text) {
  const std::filesystem::path target = writeTarget(path);
  struct stat st {};
  const mode_t mode = ::stat(target.c_str(), &st) == 0 ? (st.st_mode & 07777) : newFileMode();
  replaceFile(target, path, text, mode);
}

std::string format(double value, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, value);
  return buf;
}

void editFile(const std::string& path, const std::function<std::string(const std::string&)>& edit,
              const std::string* expected) {
  const std::filesystem::path target = writeTarget(path);
  // Lock the file, then make sure the name still refers to the locked file: a concurrent edit may
  // have renamed a new file into place while this one waited.
  int fd = -1;
  for (int attempt = 0;; ++attempt) {
    fd = ::open(target.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw UsageError(path + ": cannot read the file (" + std::strerror(errno) + ")");
    struct stat locked {}, named {};
    if (flock(fd, LOCK_EX) != 0 || fstat(fd, &locked) != 0) {
      ::close(fd);
      throw UsageError(path + ": cannot lock the file for editing (" + std::strerror(errno) + ")");
    }
    if (::stat(target.c_str(), &named) == 0 && named.st_ino == locked.st_ino && named.st_dev == locked.st_dev) break;
    ::close(fd);
    if (attempt > 1000) throw UsageError(path + ": the file keeps being replaced; edit not done");
  }
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }  // also releases the lock
  } closer{fd};
  std::string text;
  char buf[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw UsageError(path + ": cannot read the file (" + std::strerror(errno) + ")");
    if (n == 0) break;
    text.append(buf, static_cast<std::size_t>(n));
  }
  if (expected != nullptr && text != *expected)
    throw UsageError(path + ": the file changed while kccd worked on it; nothing written (run again)");
  std::string edited;
  try {
    edited = edit(text);
  } catch (const std::runtime_error& e) {
    throw UsageError(e.what());
  }
  struct stat st {};
  replaceFile(target, path, edited, fstat(fd, &st) == 0 ? (st.st_mode & 07777) : newFileMode());
}

}  // namespace kccd::cli
