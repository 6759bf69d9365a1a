// What `kccd bag export` and the overlay's bag frames share (internal): the topics of the kinds they
// read, each message's time on the chosen clock, decoding with the place named, topic choice.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "kccd/format_number.hpp"
#include "kccd/input_error.hpp"
#include "kccd/logs/decode.hpp"
#include "kccd/logs/log_reader.hpp"
#include "kccd/logs/message_definition.hpp"
#include "kccd/overlay/bags/bag_export.hpp"

namespace kccd::overlay::detail {

using logs::Value;

enum class LogKind { Other, Joints, Image, Compressed, CameraInfo };

inline LogKind logKindOf(const logs::Channel& c, const logs::Schema* s) {
  if (!s) return LogKind::Other;
  const bool ros2 = s->encoding == "ros2msg" && c.message_encoding == "cdr";
  const bool ros1 = s->encoding == "ros1msg" && c.message_encoding == "ros1";
  if (!ros1 && !ros2) return LogKind::Other;
  const std::string t = logs::normalTypeName(s->name);
  if (t == "sensor_msgs/JointState") return LogKind::Joints;
  if (t == "sensor_msgs/Image") return LogKind::Image;
  if (t == "sensor_msgs/CompressedImage") return LogKind::Compressed;
  if (t == "sensor_msgs/CameraInfo") return LogKind::CameraInfo;
  return LogKind::Other;
}

// One channel of a kind the export reads: its definitions, and what the first pass saw.
struct LogSource {
  std::string topic;
  LogKind kind = LogKind::Other;
  std::optional<logs::MessageDefinitions> types;
  bool cdr = true;
  std::size_t count = 0;
  std::vector<std::string> names;  // joints: the first message's
  bool all_velocities = true;
  std::vector<std::int64_t> times;                                // images: each message's chosen time
  std::int64_t first = std::numeric_limits<std::int64_t>::max();  // the earliest chosen time
};

// The source of a message's channel: its topic, kind, encoding and (for the kinds read) parsed
// definitions. Throws InputError naming the place and the definition's line.
inline LogSource logSourceOf(const std::string& bag, const logs::LogReader& reader, const logs::LogMessage& m) {
  LogSource s;
  s.topic = m.channel->topic;
  s.kind = logKindOf(*m.channel, m.schema);
  if (s.kind == LogKind::Other) return s;
  s.cdr = m.channel->message_encoding == "cdr";
  try {
    s.types = logs::MessageDefinitions::parse(m.schema->name, m.schema->data,
                                              s.cdr ? logs::Dialect::Ros2 : logs::Dialect::Ros1);
  } catch (const logs::DefinitionError& e) {
    throw InputError(bag + ": " + reader.place(m.offset) + ": topic " + printable(s.topic, 60) +
                     ": the definition of " + printable(m.schema->name, 60) +
                     (e.line() ? " (line " + std::to_string(e.line()) + ")" : std::string()) + ": " +
                     printable(e.what(), 200));
  }
  return s;
}

inline const Value& fieldOf(const Value& v, const char* field, const std::string& where) {
  const Value* f = v.field(field);
  if (!f) throw InputError(where + ": the message has no field '" + field + "'");
  return *f;
}

// A message's time on the chosen clock, nanoseconds; `zero` counts messages whose header stamp is
// missing or 0 (they take the log time).
inline std::int64_t messageTime(const Value& v, const logs::LogMessage& m, TimeSource source, std::size_t& zero) {
  const auto log = static_cast<std::int64_t>(std::min<std::uint64_t>(m.log_time, std::uint64_t{1} << 62));
  if (source == TimeSource::Log) return log;
  const std::optional<std::int64_t> stamp = logs::headerStamp(v);
  if (!stamp || *stamp == 0) {  // no stamp, or one left unset
    ++zero;
    return log;
  }
  return *stamp;
}

inline std::string messagePlace(const std::string& bag, const logs::LogReader& r, const logs::LogMessage& m,
                                std::size_t index) {
  return bag + ": " + r.place(m.offset) + ": topic " + printable(m.channel->topic, 60) + ": message " +
         std::to_string(index + 1);
}

inline Value decodeMessage(const LogSource& s, const logs::LogMessage& m, const std::string& at) {
  try {
    return s.cdr ? logs::decodeCdr(*s.types, m.data) : logs::decodeRos1(*s.types, m.data);
  } catch (const logs::DecodeError& e) {
    throw InputError(at + " (" + printable(m.schema->name, 60) + ") does not decode: byte " +
                     std::to_string(e.offset()) + " of its " + std::to_string(m.data.size()) + ": " +
                     printable(e.what(), 200));
  }
}

inline std::string chooseTopic(const std::map<std::uint16_t, LogSource>& sources, std::initializer_list<LogKind> kinds,
                               const std::string& given, const std::string& option, const std::string& what,
                               const std::string& bag) {
  std::vector<std::string> fits;
  for (const auto& [id, s] : sources)
    if (std::find(kinds.begin(), kinds.end(), s.kind) != kinds.end() &&
        std::find(fits.begin(), fits.end(), s.topic) == fits.end())
      fits.push_back(s.topic);
  if (!given.empty()) {
    if (std::find(fits.begin(), fits.end(), given) == fits.end())
      throw InputError(option + " " + printable(given, 60) + ": " + bag + " has no " + what + " topic of that name" +
                       (fits.empty() ? std::string(" (it has none)") : " (it has: " + [&] {
                         std::string l;
                         for (const auto& f : fits) l += (l.empty() ? "" : ", ") + printable(f, 60);
                         return l;
                       }() + ")"));
    return given;
  }
  if (fits.size() == 1) return fits.front();
  if (fits.empty()) throw InputError(bag + ": no " + what + " topic (see kccd bag info)");
  std::string l;
  for (const auto& f : fits) l += (l.empty() ? "" : ", ") + printable(f, 60);
  throw InputError(bag + ": several " + what + " topics (" + l + "): choose one with " + option);
}

// The rule every image and joint state of a topic passes to be used: its time after the previous
// used one's (the state log and frame-times files need strictly increasing times). The others are
// counted, for one warning.
struct IncreasingTimes {
  bool any = false;
  std::int64_t last = 0;
  std::size_t dropped = 0;
  bool accept(std::int64_t t) {
    if (any && t <= last) {
      ++dropped;
      return false;
    }
    any = true, last = t;
    return true;
  }
  // The warning for what was left out ("" when nothing was): `what` names the messages.
  std::string warning(const std::string& what) const {
    return dropped == 0
               ? std::string()
               : std::to_string(dropped) + " " + what + " left out: their time was not after the previous one's";
  }
};

inline std::string exactText(double v) { return shortestNumber(v); }

// Seconds since the origin, as the state log and frame-times readers take them: the nanoseconds
// divided by 1e9 (the double nearest the exact quotient: 3333500000 ns is 3.3335, where a product
// with 1e-9 gives 3.3335000000000004).
inline std::string secondsText(std::int64_t t, std::uint64_t origin) {
  return shortestNumber(static_cast<double>(t - static_cast<std::int64_t>(origin)) / 1e9);
}

inline std::vector<double> numbersOf(const Value& v) {
  std::vector<double> out;
  if (v.kind == Value::Kind::Array)
    for (const Value& x : v.items) out.push_back(x.number());
  return out;
}

// Pass 1 over a log: every channel, and for those of the kinds read their definitions, message
// count, first joint names, whether every joint state gives velocities, each image's time and the
// earliest time on the chosen clock. `damage`: where the log was cut short, if it was.
// `visit`, when given, sees every decoded joint state and image with its time and place.
using MessageVisitor = std::function<void(const LogSource&, std::uint16_t channel, const Value&, std::int64_t time,
                                          const std::string& at)>;

inline std::map<std::uint16_t, LogSource> scanLog(const std::string& bag, TimeSource time_source, std::string& damage,
                                                  const MessageVisitor& visit = {}) {
  std::map<std::uint16_t, LogSource> sources;
  std::size_t zero_probe = 0;
  const std::unique_ptr<logs::LogReader> log = logs::openLog(bag);
  logs::LogReader& reader = *log;
  logs::LogMessage m;
  while (reader.next(m)) {
    auto [it, fresh] = sources.try_emplace(m.channel->id);
    LogSource& s = it->second;
    if (fresh) s = logSourceOf(bag, reader, m);
    if (s.kind == LogKind::Other) continue;
    const std::string at = messagePlace(bag, reader, m, s.count);
    ++s.count;
    if (s.kind == LogKind::CameraInfo) continue;
    const Value v = decodeMessage(s, m, at);
    const std::int64_t t = messageTime(v, m, time_source, zero_probe);
    s.first = std::min(s.first, t);
    if (visit) visit(s, m.channel->id, v, t, at);
    if (s.kind == LogKind::Joints) {
      const Value& names = fieldOf(v, "name", at);
      const std::size_t n = names.items.size();
      if (s.count == 1)
        for (const Value& x : names.items) s.names.push_back(x.s);
      if (numbersOf(fieldOf(v, "velocity", at)).size() != n) s.all_velocities = false;
    } else {
      s.times.push_back(t);
    }
  }
  damage = reader.damage();
  return sources;
}

// The channel of a topic, or null.
inline const LogSource* sourceOf(const std::map<std::uint16_t, LogSource>& sources, const std::string& topic) {
  for (const auto& [id, s] : sources)
    if (s.topic == topic) return &s;
  return nullptr;
}

// The median interval's rate of strictly increasing times (30 when there is none).
inline double nominalFps(const std::vector<std::int64_t>& times) {
  std::vector<std::int64_t> d;
  for (std::size_t i = 1; i < times.size(); ++i)
    if (times[i] > times[i - 1]) d.push_back(times[i] - times[i - 1]);
  std::sort(d.begin(), d.end());
  return d.empty() ? 30.0 : std::clamp(1e9 / static_cast<double>(d[d.size() / 2]), 0.1, 1000.0);
}

// A joint state's values in `columns` order: the positions, then (with `velocities`) the
// velocities, NaN where the message gives none. Joints not in `columns` are counted in `extra`.
// Throws InputError naming `at` for a column the message does not name or a value not finite.
inline std::vector<double> jointRow(const Value& v, const std::string& at, const std::vector<std::string>& columns,
                                    bool velocities, std::size_t& extra) {
  const Value& names = fieldOf(v, "name", at);
  const std::vector<double> pos = numbersOf(fieldOf(v, "position", at)), vel = numbersOf(fieldOf(v, "velocity", at));
  if (pos.size() != names.items.size())
    throw InputError(at + ": " + std::to_string(names.items.size()) + " names but " + std::to_string(pos.size()) +
                     " positions");
  std::vector<double> row(columns.size() * (velocities ? 2 : 1), std::nan(""));
  for (std::size_t i = 0; i < names.items.size(); ++i) {
    const auto c = std::find(columns.begin(), columns.end(), names.items[i].s);
    if (c == columns.end()) {
      ++extra;
      continue;
    }
    const std::size_t col = static_cast<std::size_t>(c - columns.begin());
    row[col] = pos[i];
    if (velocities && i < vel.size()) row[columns.size() + col] = vel[i];
  }
  for (std::size_t col = 0; col < row.size(); ++col) {
    if (std::isnan(row[col]) && col < columns.size())
      throw InputError(at + ": joint '" + printable(columns[col], 60) + "' is not given");
    if (col >= columns.size() && std::isnan(row[col])) continue;  // no velocity: the caller decides
    if (!std::isfinite(row[col]) || std::abs(row[col]) > 1e300)
      throw InputError(at + ": joint '" + printable(columns[col % columns.size()], 60) +
                       "': " + (col < columns.size() ? "position " : "velocity ") + formatNumber(row[col], 6) +
                       " is not a finite number");
  }
  return row;
}

}  // namespace kccd::overlay::detail
