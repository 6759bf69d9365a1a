// The model file a kccd subcommand reads.
#pragma once

#include <string>

#include "kccd/model.hpp"

namespace kccd::cli {

/// Loads a model, turning every failure into one line on stderr (throws UsageError); with `text`,
/// also returns the file's text as it was read.
Model loadOrExplain(const std::string& path, std::string* text = nullptr);

}  // namespace kccd::cli
