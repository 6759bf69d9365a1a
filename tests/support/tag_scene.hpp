// The tag scene renderer (kccd/overlay/synth/tag_scene.hpp, the room of `kccd synth`) under the names the
// image tests use.
#pragma once

#include "kccd/overlay/synth/tag_scene.hpp"

namespace kccd::testing {

using overlay::distortNormalised;
using overlay::projectTagCorners;
using overlay::renderTagScene;
using overlay::TagSceneOptions;

}  // namespace kccd::testing
