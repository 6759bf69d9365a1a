// libFuzzer target: kccd::modelling::readPart on arbitrary bytes, as .iv or .wrl (Coin3D), .stl
// (read directly), or .obj, .dae, .ply, .glb, .gltf (Assimp), chosen by the first byte. A result
// or the reader's one-line std::runtime_error is fine; a crash, any other exception or a
// multi-line message is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include "fuzz_support.hpp"
#include "kccd/input_error.hpp"
#include "kccd/modelling/convex_pieces.hpp"
#include "kccd/modelling/part.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  static const char* const extensions[] = {".iv", ".wrl", ".stl", ".obj", ".dae", ".ply", ".glb", ".gltf"};
  const std::string path =
      kccd::fuzz::writeInput("fuzz_part", std::string("input") + extensions[data[0] % 8], data + 1, size - 1);
  try {
    kccd::modelling::ReadOptions options;
    options.merge = (data[0] & 8) != 0;
    options.mesh_time_limit_s = 4.0;  // an endless Assimp read ends well within libFuzzer's timeout
    const kccd::modelling::Part part = kccd::modelling::readPart(path, options);
    // One input in four: the mesh read is split into convex pieces as kccd import would (coarse,
    // to leave the readers most of the time).
    if ((data[0] & 0x30) == 0 && part.faces.size() <= 20000)
      (void)kccd::modelling::splitConcave(part, {.max_pieces = 4, .concavity = 1e-9, .resolution = 12});
  } catch (const kccd::InputError& e) {
    kccd::fuzz::checkMessage(e.what(), path);
  }
  return 0;
}
