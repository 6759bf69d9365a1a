// libFuzzer target: the model loader. Contract: any input either loads (and the model then
// answers a query at its zero state with a status, never a crash) or throws one ModelError whose
// message is one printable line naming the source.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "fuzz_support.hpp"
#include "kccd/checker.hpp"
#include "kccd/model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const kccd::Model m = kccd::parseModel(text, "fuzz.yaml");
    kccd::Checker checker(m);
    const std::vector<double> zero(static_cast<std::size_t>(m.stateSize()), 0.0);
    const kccd::QueryResult& r = checker.query(zero, zero, {.type = kccd::QueryType::Distances});
    if (r.status != kccd::Status::Ok && !r.collision) std::abort();  // a failed status must say "unsafe"
  } catch (const kccd::ModelError& e) {
    kccd::fuzz::checkMessage(e.what(), "fuzz.yaml");
  }
  return 0;
}
