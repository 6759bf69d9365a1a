#include "kccd/overlay/recording/frame_times.hpp"

#include <cmath>
#include <cstdlib>
#include <limits>

#include "kccd/file_reader.hpp"

namespace kccd::overlay {
namespace {

// A field for a message: one printable line.
std::string shown(std::string_view text) {
  std::string flat(text);
  for (char& c : flat)
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  return printable(flat, 80);
}

}  // namespace

std::vector<double> parseFrameTimes(std::string_view text, const std::string& name) {
  const std::string file = printable(name, 400);
  const auto fail = [&](long line, std::size_t column, const char* field, const std::string& problem) {
    throw FrameTimesError(InputLocation{file, static_cast<std::size_t>(line), column, field}, problem);
  };
  std::vector<double> times;
  long line_no = 0, last_frame = -1;
  double last_time = -std::numeric_limits<double>::infinity();
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t eol = text.find('\n', at);
    std::string_view line = text.substr(at, eol == std::string_view::npos ? std::string_view::npos : eol - at);
    at = eol == std::string_view::npos ? text.size() : eol + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line_no == 1) {
      if (line.substr(0, 3) == "\xEF\xBB\xBF") line.remove_prefix(3);
      if (line != "frame,time") fail(1, 1, "", "the header must be 'frame,time' (found '" + shown(line) + "')");
      continue;
    }
    if (line.empty()) {
      if (at >= text.size()) break;  // a final empty line
      fail(line_no, 1, "", "empty line");
    }
    const std::size_t comma = line.find(',');
    if (comma == std::string_view::npos || line.find(',', comma + 1) != std::string_view::npos)
      fail(line_no, 1, "", "expected two fields: frame,time");
    const std::string_view f = line.substr(0, comma), t = line.substr(comma + 1);
    if (f.empty() || f.size() > 12 || f.find_first_not_of("0123456789") != std::string_view::npos)
      fail(line_no, 1, "column 'frame'", "not a frame number: '" + shown(f) + "'");
    const long frame = std::strtol(std::string(f).c_str(), nullptr, 10);
    const std::string tstr(t);
    char* end = nullptr;
    const double time = std::strtod(tstr.c_str(), &end);
    const std::size_t tcol = comma + 2;
    if (tstr.empty() || end != tstr.c_str() + tstr.size() || !std::isfinite(time) || std::fabs(time) > 1e300)
      fail(line_no, tcol, "column 'time'", "not a finite number: '" + shown(t) + "'");
    if (frame != last_frame + 1)
      fail(line_no, 1, "column 'frame'",
           "expected frame " + std::to_string(last_frame + 1) + ", found " + std::to_string(frame) +
               " (one row per frame, from 0, in order)");
    if (!(time > last_time)) fail(line_no, tcol, "column 'time'", "times must increase strictly");
    if (frame > kMaxFrameNumber) fail(line_no, 1, "column 'frame'", "frame number too large");
    last_frame = frame;
    last_time = time;
    times.push_back(time);
  }
  if (times.empty()) throw FrameTimesError(InputLocation{file, 0, 0, {}}, "no rows");
  return times;
}

std::vector<double> loadFrameTimes(const std::string& path) {
  std::string text;
  try {
    text = readRegularFile(path, kMaxFrameTimesBytes, "frame-times file");
  } catch (const FileError& e) {
    throw FrameTimesError(e.location(), e.problem());
  }
  return parseFrameTimes(text, path);
}

}  // namespace kccd::overlay
