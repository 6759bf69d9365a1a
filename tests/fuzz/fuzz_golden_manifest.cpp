// libFuzzer target: golden manifests (kccd golden). Any input must parse or be rejected with
// kccd::InputError whose message names the manifest; a parsed one must hold what the reader
// promises (unique ids that are folder names, one kind of case each, tolerances in range).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <set>
#include <string>

#include "fuzz_support.hpp"
#include "kccd/input_error.hpp"
#include "kccd/overlay/golden/golden_manifest.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const std::string path = "fuzz/golden.yaml";
  try {
    const kccd::overlay::GoldenManifest m = kccd::overlay::parseGoldenManifest(text, path);
    std::set<std::string> ids;
    if (m.cases.empty()) std::abort();
    for (const kccd::overlay::GoldenCase& c : m.cases) {
      if (!ids.insert(c.id).second || c.id.empty() || c.id.find('/') != std::string::npos || c.id[0] == '.')
        std::abort();
      const int kinds = !c.state.empty() + !c.lower.empty() + c.hasVideo();
      if (kinds != 1 || c.lower.size() != c.upper.size() || c.model.empty() || c.camera.empty() || c.outputs.empty())
        std::abort();
      for (std::size_t k = 0; k < c.lower.size(); ++k)
        if (!(c.lower[k] <= c.upper[k])) std::abort();
      if (c.hasVideo() && (c.frame < 0 || c.states.empty())) std::abort();
      if (c.colour.channel_threshold < 0 || c.colour.channel_threshold > 255 || c.mask.max_cluster_px < 0) std::abort();
    }
  } catch (const kccd::InputError& e) {
    kccd::fuzz::checkMessage(e.what(), path);
  }
  return 0;
}
