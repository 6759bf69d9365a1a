#include "cli_model.hpp"

#include "cli_args.hpp"

namespace kccd::cli {

Model loadOrExplain(const std::string& path, std::string* text) {
  try {
    if (text == nullptr) return loadModel(path);
    *text = readModelText(path);
    return parseModel(*text, path);
  } catch (const InputError& e) {
    throw UsageError(e.what());
  }
}

}  // namespace kccd::cli
