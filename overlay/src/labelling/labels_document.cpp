#include "kccd/overlay/labelling/labels_document.hpp"

namespace kccd::overlay {
namespace {

// A value as JSON text; a string that is not UTF-8 cannot come from a JSON parser, but is
// written with replacement characters rather than thrown on.
std::string flow(const nlohmann::json& value) {
  return value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace

std::string labelsYaml(const nlohmann::json& document, const std::string& source) {
  if (!document.is_object())
    throw calib::LabelsError(InputLocation{source, 0, 0, "file"}, "expected a JSON object {\"labels\": [...]}");
  std::string text;
  for (const auto& [key, value] : document.items()) {
    if (key != "labels") {
      text += flow(key) + ": " + flow(value) + "\n";
      continue;
    }
    if (!value.is_array())
      throw calib::LabelsError(InputLocation{source, 0, 0, "labels"},
                               "expected a list of {name, pixel, world} or {name, pixel, body, point, state}");
    if (value.empty()) {
      text += "labels: []\n";
      continue;
    }
    text += "labels:\n";
    for (const nlohmann::json& label : value) text += "  - " + flow(label) + "\n";
  }
  return text;
}

bool emptyLabels(const nlohmann::json& document) {
  if (!document.is_object()) return false;
  const auto it = document.find("labels");
  return it != document.end() && it->is_array() && it->empty();
}

nlohmann::json labelsJson(const calib::Labels& labels) {
  nlohmann::json list = nlohmann::json::array();
  for (const calib::Label& l : labels.labels) {
    nlohmann::json j;
    j["name"] = l.name;
    j["pixel"] = {l.pixel.x, l.pixel.y};
    if (l.world) {
      j["world"] = {l.world->x, l.world->y, l.world->z};
    } else {
      j["body"] = l.body;
      j["point"] = {l.point.x, l.point.y, l.point.z};
      if (l.state) j["state"] = *l.state;
    }
    list.push_back(std::move(j));
  }
  return nlohmann::json{{"labels", std::move(list)}};
}

calib::Labels parseLabelsDocument(const nlohmann::json& document, const std::string& source) {
  return calib::parseLabels(labelsYaml(document, source), source);
}

}  // namespace kccd::overlay
