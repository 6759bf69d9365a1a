// libFuzzer target: labels documents as the labelling page sends them (PUT /api/labels): any body
// is either not JSON (the server's 400 before this point), or turned into the labels file's text
// and then loaded or rejected with calib::LabelsError, never anything else. A document that loads
// must give the same labels when written back from them (labelsJson -> labelsYaml -> parseLabels):
// the round trip the page and the saved file rely on.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include <nlohmann/json.hpp>

#include "kccd/calib/labels.hpp"
#include "kccd/overlay/labelling/labels_document.hpp"

namespace {

bool same(const kccd::calib::Labels& a, const kccd::calib::Labels& b) {
  if (a.labels.size() != b.labels.size()) return false;
  for (std::size_t i = 0; i < a.labels.size(); ++i) {
    const kccd::calib::Label& x = a.labels[i];
    const kccd::calib::Label& y = b.labels[i];
    if (x.name != y.name || x.pixel != y.pixel || x.world != y.world || x.body != y.body || x.state != y.state)
      return false;
    if (!x.world && x.point != y.point) return false;
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const nlohmann::json doc = nlohmann::json::parse(data, data + size, nullptr, false);
  if (doc.is_discarded()) return 0;
  try {
    const kccd::calib::Labels labels = kccd::overlay::parseLabelsDocument(doc, "labels.yaml");
    const kccd::calib::Labels again =
        kccd::overlay::parseLabelsDocument(kccd::overlay::labelsJson(labels), "labels.yaml");
    if (!same(labels, again)) std::abort();  // the round trip lost or changed something
  } catch (const kccd::calib::LabelsError&) {
    // rejected with a message: fine
  }
  return 0;
}
