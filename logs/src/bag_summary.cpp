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

// One channel's messages as they are read.
struct TopicState {
  TopicSummary summary;
  std::optional<MessageDefinitions> types;
  bool cdr = false;
  std::vector<double> skews;  // seconds
};

// A channel's row from its first message: topic, type, where the definition comes from, whether
// its stamps can be read (the definition parsed).
void startChannel(TopicState& t, const LogMessage& m, const std::string& path, const LogReader& reader) {
  TopicSummary& s = t.summary;
  s.topic = m.channel->topic;
  s.message_encoding = m.channel->message_encoding;
  if (m.schema) s.type = m.schema->name, s.schema_encoding = m.schema->encoding, s.definition = "stored";
  for (const auto& [k, v] : m.channel->metadata) {
    if (k == "kccd_definition" && v == "built in") s.definition = "built in";
    if (k == "kccd_no_definition" && !m.schema) s.type = v;
    if (!k.starts_with("kccd_")) s.metadata.emplace_back(k, v);  // the readers' own markers stay inside
  }
  const bool ros2 = m.schema && m.schema->encoding == "ros2msg" && m.channel->message_encoding == "cdr";
  const bool ros1 = m.schema && m.schema->encoding == "ros1msg" && m.channel->message_encoding == "ros1";
  if (!m.schema) {
    s.no_stamps = "no definition in the log";
    return;
  }
  if (!ros1 && !ros2) {
    s.no_stamps = "schema " + m.schema->encoding + ", messages " + m.channel->message_encoding + ": not decoded";
    return;
  }
  try {
    t.types = MessageDefinitions::parse(m.schema->name, m.schema->data, ros2 ? Dialect::Ros2 : Dialect::Ros1);
  } catch (const DefinitionError& e) {
    throw InputError(InputLocation{path, 0, 0, reader.place(m.offset)},
                     "topic " + printable(s.topic, 60) + ": the definition of " + printable(m.schema->name, 60) +
                         (e.line() > 0 ? " (line " + std::to_string(e.line()) + " of its schema)" : std::string()) +
                         ": " + printable(e.what(), 200));
  }
  t.cdr = ros2;
  const Field* first = t.types->root().fields.empty() ? nullptr : &t.types->root().fields.front();
  if (!first || first->name != "header") s.no_stamps = "no header";
}

// One message counted in its channel's row, its header stamp (where it has one) in the skews.
void countMessage(TopicState& t, const LogMessage& m, const std::string& path, const LogReader& reader) {
  TopicSummary& s = t.summary;
  if (s.count == 0 || m.log_time < s.first_log_time) s.first_log_time = m.log_time;
  s.last_log_time = std::max(s.last_log_time, m.log_time);
  ++s.count;
  if (!t.types || !s.no_stamps.empty()) return;
  Value v;
  try {
    v = t.cdr ? decodeCdr(*t.types, m.data) : decodeRos1(*t.types, m.data);
  } catch (const DecodeError& e) {
    throw InputError(InputLocation{path, 0, 0, reader.place(m.offset)},
                     "topic " + printable(s.topic, 60) + " (" + printable(s.type, 60) + "): message " +
                         std::to_string(s.count) + " does not decode: byte " + std::to_string(e.offset()) + " of its " +
                         std::to_string(m.data.size()) + ": " + printable(e.what(), 200));
  }
  const auto stamp = headerStamp(v);
  if (!stamp) return;
  ++s.stamped;
  if (*stamp == 0) {
    ++s.zero_stamps;
    return;
  }
  // Nanoseconds subtracted exactly (both within 2^62), then divided: 35 ms reads 0.035.
  const auto log = static_cast<std::int64_t>(std::min<std::uint64_t>(m.log_time, std::uint64_t{1} << 62));
  const std::int64_t stamped = std::clamp<std::int64_t>(*stamp, -(std::int64_t{1} << 62), std::int64_t{1} << 62);
  t.skews.push_back(static_cast<double>(log - stamped) / 1e9);
}

// Least, median and most of `skews` (sorted here) into `s`.
void setSkews(TopicSummary& s, std::vector<double>& skews) {
  if (skews.empty()) return;
  std::sort(skews.begin(), skews.end());
  s.skew_min = skews.front();
  s.skew_max = skews.back();
  s.skew_median = skews[skews.size() / 2];
}

// A channel's text field into its topic's `to`: the first channel's value, then each value not in
// it yet after ", " (two nodes that publish a topic in two types show both).
void addDistinct(std::string& to, const std::string& value, bool first) {
  if (first) {
    to = value;
    return;
  }
  if (value.empty()) return;
  const std::string list = ", " + to + ", ";
  if (list.find(", " + value + ", ") == std::string::npos) to = to.empty() ? value : to + ", " + value;
}

// A topic's row from its channels' (in the order the log defines them): their counts summed, their
// time spans joined, the skews over all their stamps; the channels' rows as its publishers.
TopicSummary topicOf(const std::vector<TopicState*>& channels) {
  TopicSummary out;
  std::vector<double> skews;
  for (TopicState* t : channels) {
    setSkews(t->summary, t->skews);
    const TopicSummary& s = t->summary;
    const bool first = out.publishers.empty();
    out.topic = s.topic;
    addDistinct(out.type, s.type, first);
    addDistinct(out.schema_encoding, s.schema_encoding, first);
    addDistinct(out.message_encoding, s.message_encoding, first);
    addDistinct(out.no_stamps, s.no_stamps, first);
    addDistinct(out.definition, s.definition, first);
    if (first || s.first_log_time < out.first_log_time) out.first_log_time = s.first_log_time;
    out.last_log_time = std::max(out.last_log_time, s.last_log_time);
    out.count += s.count;
    out.stamped += s.stamped;
    out.zero_stamps += s.zero_stamps;
    skews.insert(skews.end(), t->skews.begin(), t->skews.end());
    out.publishers.push_back(s);
  }
  setSkews(out, skews);
  return out;
}

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
    if (fresh) startChannel(it->second, m, path, reader);
    countMessage(it->second, m, path, reader);
  }
  out.damage = reader.damage();
  out.profile = reader.profile();
  out.library = reader.library();
  out.chunks = reader.chunks();
  // One row per topic, however many channels (publishers) carry it.
  std::map<std::string, std::vector<TopicState*>> by_topic;
  for (auto& [id, t] : by_channel) by_topic[t.summary.topic].push_back(&t);
  for (const auto& [name, channels] : by_topic) {
    TopicSummary s = topicOf(channels);
    if (out.messages == 0 || s.first_log_time < out.first_log_time) out.first_log_time = s.first_log_time;
    out.last_log_time = std::max(out.last_log_time, s.last_log_time);
    out.messages += s.count;
    out.topics.push_back(std::move(s));
  }
  return out;
}

}  // namespace kccd::logs
