#include "kccd/logs/bag_summary.hpp"

#include <algorithm>
#include <memory>
#include <optional>

#include "kccd/input_error.hpp"
#include "kccd/logs/decode.hpp"
#include "kccd/logs/log_reader.hpp"
#include "kccd/logs/message_definition.hpp"

namespace kccd::logs {

double TopicSummary::rate() const {
  if (count < 2 || last_log_time <= first_log_time) return 0.0;
  return static_cast<double>(count - 1) / (1e-9 * static_cast<double>(last_log_time - first_log_time));
}

namespace {

struct TopicState {
  TopicSummary summary;
  std::optional<MessageDefinitions> types;
  bool cdr = false;
  std::vector<double> skews;  // seconds
};

}  // namespace

BagSummary summarizeBag(const std::string& path) {
  const std::unique_ptr<LogReader> log = openLog(path);
  LogReader& reader = *log;
  BagSummary out;
  out.path = path;
  out.format = reader.format();
  std::map<std::uint16_t, TopicState> by_channel;
  LogMessage m;
  while (reader.next(m)) {
    auto [it, fresh] = by_channel.try_emplace(m.channel->id);
    TopicState& t = it->second;
    if (fresh) {
      t.summary.topic = m.channel->topic;
      t.summary.message_encoding = m.channel->message_encoding;
      if (m.schema)
        t.summary.type = m.schema->name, t.summary.schema_encoding = m.schema->encoding,
        t.summary.definition = "stored";
      for (const auto& [k, v] : m.channel->metadata)
        if (k == "kccd_definition" && v == "built in") t.summary.definition = "built in";
      if (!m.schema)
        for (const auto& [k, v] : m.channel->metadata)
          if (k == "kccd_no_definition") t.summary.type = v;
      const bool ros2 = m.schema && m.schema->encoding == "ros2msg" && m.channel->message_encoding == "cdr";
      const bool ros1 = m.schema && m.schema->encoding == "ros1msg" && m.channel->message_encoding == "ros1";
      if (!m.schema)
        t.summary.no_stamps = "no definition in the log";
      else if (!ros1 && !ros2)
        t.summary.no_stamps =
            "schema " + m.schema->encoding + ", messages " + m.channel->message_encoding + ": not decoded";
      else {
        try {
          t.types = MessageDefinitions::parse(m.schema->name, m.schema->data, ros2 ? Dialect::Ros2 : Dialect::Ros1);
        } catch (const DefinitionError& e) {
          throw InputError(
              InputLocation{path, 0, 0, reader.place(m.offset)},
              "topic " + printable(t.summary.topic, 60) + ": the definition of " + printable(m.schema->name, 60) +
                  (e.line() > 0 ? " (line " + std::to_string(e.line()) + " of its schema)" : std::string()) + ": " +
                  printable(e.what(), 200));
        }
        t.cdr = ros2;
        const Field* first = t.types->root().fields.empty() ? nullptr : &t.types->root().fields.front();
        const bool has_header = first && first->name == "header";
        if (!has_header) t.summary.no_stamps = "no header";
      }
    }
    TopicSummary& s = t.summary;
    if (s.count == 0 || m.log_time < s.first_log_time) s.first_log_time = m.log_time;
    s.last_log_time = std::max(s.last_log_time, m.log_time);
    ++s.count;
    if (t.types && s.no_stamps.empty()) {
      Value v;
      try {
        v = t.cdr ? decodeCdr(*t.types, m.data) : decodeRos1(*t.types, m.data);
      } catch (const DecodeError& e) {
        throw InputError(InputLocation{path, 0, 0, reader.place(m.offset)},
                         "topic " + printable(s.topic, 60) + " (" + printable(s.type, 60) + "): message " +
                             std::to_string(s.count) + " does not decode: byte " + std::to_string(e.offset()) +
                             " of its " + std::to_string(m.data.size()) + ": " + printable(e.what(), 200));
      }
      if (const auto stamp = headerStamp(v)) {
        ++s.stamped;
        if (*stamp == 0)
          ++s.zero_stamps;
        else {
          // Nanoseconds subtracted exactly (both within 2^62), then divided: 35 ms reads 0.035.
          const auto log = static_cast<std::int64_t>(std::min<std::uint64_t>(m.log_time, std::uint64_t{1} << 62));
          const std::int64_t stamped =
              std::clamp<std::int64_t>(*stamp, -(std::int64_t{1} << 62), std::int64_t{1} << 62);
          t.skews.push_back(static_cast<double>(log - stamped) / 1e9);
        }
      }
    }
  }
  out.damage = reader.damage();
  out.profile = reader.profile();
  out.library = reader.library();
  out.chunks = reader.chunks();
  for (auto& [id, t] : by_channel) {
    if (!t.skews.empty()) {
      std::sort(t.skews.begin(), t.skews.end());
      t.summary.skew_min = t.skews.front();
      t.summary.skew_max = t.skews.back();
      t.summary.skew_median = t.skews[t.skews.size() / 2];
    }
    TopicSummary& s = t.summary;
    if (out.messages == 0 || s.first_log_time < out.first_log_time) out.first_log_time = s.first_log_time;
    out.last_log_time = std::max(out.last_log_time, s.last_log_time);
    out.messages += s.count;
    out.topics.push_back(std::move(s));
  }
  std::sort(out.topics.begin(), out.topics.end(),
            [](const TopicSummary& a, const TopicSummary& b) { return a.topic < b.topic; });
  return out;
}

}  // namespace kccd::logs
