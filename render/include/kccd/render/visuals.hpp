// A model's visual geometry (Model::visuals) as drawable meshes: mesh files read once, primitives
// tessellated, placed per configuration.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/input_error.hpp"
#include "kccd/model.hpp"
#include "kccd/render/mesh.hpp"
#include "kccd/render/render_types.hpp"

namespace kccd::render {

/// A visual that cannot be drawn: its message names the visual (`visuals[i]`) and the mesh file.
class VisualError : public InputError {
 public:
  using InputError::InputError;
};

/// One visual ready to draw: its mesh in its frame (origin and scale applied), colour (BGR, 0..255)
/// and the mask label of the first body in the same frame (0 when the frame has none).
struct LoadedVisual {
  int frame = kWorld;                ///< the joint frame it moves with (kWorld: fixed)
  std::shared_ptr<const Mesh> mesh;  ///< its triangles in that frame
  cv::Scalar colour;                 ///< BGR, 0..255
  int label = 0;                     ///< mask label: the first body in its frame + 1, else 0
};

/// Reads every mesh file of the model's visuals (through modelling::readPart, so the same formats
/// and errors as `kccd fit`) and tessellates boxes, cylinders and spheres. Throws VisualError with
/// one line naming the visual and the file.
std::vector<LoadedVisual> loadVisuals(const Model& model);

/// The visuals placed at a configuration (frame poses from kccd::framePoses); an empty list when
/// the state is not a valid configuration.
std::vector<Volume> visualVolumes(const Model& model, std::span<const LoadedVisual> visuals,
                                  std::span<const double> state);

}  // namespace kccd::render
