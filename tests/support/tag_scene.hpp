// The tag scene renderer (kccd/calib/tag_scene.hpp, the room of `kccd synth`) under the names the
// image tests use.
#pragma once

#include "kccd/calib/tag_scene.hpp"

namespace kccd::testing {

using calib::distortNormalised;
using calib::projectTagCorners;
using calib::renderTagScene;
using calib::TagSceneOptions;

}  // namespace kccd::testing
