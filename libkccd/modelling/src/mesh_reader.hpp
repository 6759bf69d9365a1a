// Triangle meshes read through Assimp (OBJ, COLLADA, PLY, glTF/GLB and the other formats Assimp
// reads), for readPart.
#pragma once

#include <string>

#include "kccd/modelling/part.hpp"

namespace kccd::modelling::detail {

/// Whether Assimp reads files with this extension (lower case, with the dot); Open Inventor and
/// VRML are left to Coin3D.
bool readsAsMesh(const std::string& extension);

/// The triangles of the mesh file at `path` (whose bytes, `data`, the caller has read and
/// checked; named `name` in messages; `extension` choosing the format: only Assimp's readers
/// for it are tried; files it names are looked up beside it), every node transform applied and then options.scale;
/// options.part picks a node by name, several top-level nodes with triangles need options.merge. COLLADA: the `<unit
/// meter>` scale is applied and `<up_axis>` is not (the file's coordinates are the link frame's, as ROS tools place
/// them). Throws PartError with one line naming the file.
Part readMesh(const std::string& data, const std::string& path, const std::string& name, const std::string& extension,
              const ReadOptions& options);

}  // namespace kccd::modelling::detail
