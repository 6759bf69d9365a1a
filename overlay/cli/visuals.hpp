// Moved to kccd/render/visuals.hpp (namespace kccd::render); kept for the commands that include it here.
#pragma once

#include "kccd/render/visuals.hpp"

namespace kccd::cli {
using render::LoadedVisual;
using render::loadVisuals;
using render::visualVolumes;
}  // namespace kccd::cli
