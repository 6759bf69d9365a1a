#include "kccd/overlay/bags/bag_info.hpp"

#include <string>

namespace kccd::overlay {
namespace {

// What a topic's row and each of its publishers' rows say alike: type, count, times, rate, stamps.
nlohmann::json rowJson(const logs::TopicSummary& t) {
  nlohmann::json o{{"type", t.type},
                   {"count", t.count},
                   {"first_log_time_ns", std::to_string(t.first_log_time)},
                   {"last_log_time_ns", std::to_string(t.last_log_time)},
                   {"rate_hz", t.rate()},
                   {"stamped", t.stamped},
                   {"zero_stamps", t.zero_stamps}};
  if (t.stamped > t.zero_stamps) o["skew_s"] = {{"min", t.skew_min}, {"median", t.skew_median}, {"max", t.skew_max}};
  if (!t.no_stamps.empty()) o["no_stamps"] = t.no_stamps;
  return o;
}

}  // namespace

nlohmann::json bagInfoJson(const logs::BagSummary& b) {
  nlohmann::json j;
  j["bag"] = b.path;
  j["format"] = b.format;
  j["profile"] = b.profile;
  j["library"] = b.library;
  j["messages"] = b.messages;
  // Nanoseconds as decimal strings: JSON readers keep 53 bits of a number.
  j["first_log_time_ns"] = std::to_string(b.first_log_time);
  j["last_log_time_ns"] = std::to_string(b.last_log_time);
  j["duration_s"] = b.messages > 0 ? 1e-9 * static_cast<double>(b.last_log_time - b.first_log_time) : 0.0;
  j["chunks"] = b.chunks;
  j["damage"] = b.damage.empty() ? nlohmann::json() : nlohmann::json(b.damage);
  j["topics"] = nlohmann::json::array();
  for (const logs::TopicSummary& t : b.topics) {
    nlohmann::json o = rowJson(t);
    o["topic"] = t.topic;
    o["schema_encoding"] = t.schema_encoding;
    o["message_encoding"] = t.message_encoding;
    o["definition"] = t.definition;
    o["publishers"] = nlohmann::json::array();
    for (const logs::TopicSummary& p : t.publishers) {
      nlohmann::json r = rowJson(p);
      r["metadata"] = nlohmann::json::object();
      for (const auto& [k, v] : p.metadata) r["metadata"][k] = v;
      o["publishers"].push_back(r);
    }
    j["topics"].push_back(o);
  }
  return j;
}

}  // namespace kccd::overlay
