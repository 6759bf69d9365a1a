#include "kccd/overlay/recording/status_line.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "kccd/input_error.hpp"
#include "kccd/render/render_types.hpp"

namespace kccd::overlay {
namespace {

// The fields kept, each joined to the one before by its separator.
std::string joined(const std::vector<StatusField>& fields, const std::vector<bool>& kept) {
  std::string s;
  for (std::size_t i = 0; i < fields.size(); ++i)
    if (kept[i]) s += (s.empty() ? "" : fields[i].separator) + fields[i].text;
  return s;
}

// `text`'s first `n` words (split at spaces) and " ...", a trailing comma or colon dropped.
std::string firstWords(const std::string& text, std::size_t n) {
  std::size_t end = 0;
  for (std::size_t k = 0; k < n; ++k) {
    end = text.find(' ', end + (k ? 1 : 0));
    if (end == std::string::npos) return text;
  }
  std::string kept = text.substr(0, end);
  while (!kept.empty() && (kept.back() == ',' || kept.back() == ':')) kept.pop_back();
  return kept + " ...";
}

std::size_t words(const std::string& text) { return 1 + std::count(text.begin(), text.end(), ' '); }

}  // namespace

std::vector<StatusField> statusFields(const FrameRecord& rec, const Model& model, const AnnotatorSettings& set) {
  std::vector<StatusField> f;
  char buf[64];
  std::snprintf(buf, sizeof buf, "t %.3f s", rec.time + set.time_offset);
  f.push_back({buf, 3});
  if (rec.match == StateMatch::None) {
    f.push_back({"NO STATE", 0});
    f.push_back({"(outside the log or in a gap longer than " + messageNumber(set.max_gap, 3) + " s)", 5, " ", 0, true});
    return f;
  }
  f.push_back({std::string("(") + toString(rec.match) + ")", 5, " ", 0, true});
  if (set.swept) f.push_back({"swept", 4});
  if (rec.unsafe()) {
    f.push_back({std::string("UNSAFE: ") + (rec.braking_failed ? "no braking box"
                                            : rec.not_finite   ? "volume not finite"
                                                               : toString(rec.query)),
                 0});
    return f;
  }
  if (std::isfinite(rec.min_distance)) {
    std::snprintf(buf, sizeof buf, "min distance %.4f m", rec.min_distance);
    f.push_back({buf, 0});
  } else {
    f.push_back({"no checked pairs", 0});
  }
  if (!rec.pairs.empty()) {
    std::string pairs = "within margin: ";
    const std::vector<std::array<std::string, 2>> links = linkPairs(model, rec.pairs);
    for (std::size_t i = 0; i < links.size() && i < 3; ++i) pairs += (i ? ", " : "") + links[i][0] + "-" + links[i][1];
    if (links.size() > 3) pairs += " +" + std::to_string(links.size() - 3);
    f.push_back({pairs, 1, "  ", 3});  // "within margin:" and one pair at least
  }
  return f;
}

std::string fitStatus(std::vector<StatusField> fields, int max_width,
                      const std::function<int(const std::string&)>& width) {
  std::vector<std::size_t> order(fields.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return fields[a].rank < fields[b].rank; });
  std::vector<bool> kept(fields.size(), false);
  const auto fits = [&] { return width(joined(fields, kept)) <= max_width; };
  bool first = true;
  for (const std::size_t i : order) {
    StatusField& f = fields[i];
    if (f.with_previous && (i == 0 || !kept[i - 1])) continue;
    kept[i] = true;
    if (fits()) {
      first = false;
      continue;
    }
    const std::size_t keep = first ? 1 : f.cut_keeping;
    const std::string whole = f.text;
    bool cut = false;
    for (std::size_t n = words(whole) - 1; keep > 0 && n >= keep && !cut; --n) {
      f.text = firstWords(whole, n);
      cut = fits();
    }
    if (!cut) {
      f.text = whole;
      kept[i] = false;
    }
    first = first && !cut;
  }
  return joined(fields, kept);
}

cv::Scalar statusTextColour(SafetyStatus status) {
  return status == SafetyStatus::Clear ? cv::Scalar(255, 255, 255) : render::statusColour(status);
}

}  // namespace kccd::overlay
