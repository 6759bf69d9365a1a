// libFuzzer target: kccd::modelling::importUrdf on arbitrary bytes. A model or the importer's
// one-line std::runtime_error is fine; a crash, any other exception or a multi-line message is a
// finding.
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
#include "kccd/modelling/urdf_import.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = kccd::fuzz::writeInput("fuzz_urdf", "input.urdf", data, size);
  try {
    // One core point and a 1 m tolerance: the fits stay quick (the simplified hull meets it with
    // four points, the K = 1 fit is tried); meshes are looked up next to the input (none there).
    (void)kccd::modelling::importUrdf(
        path,
        {.fit = {.method = kccd::modelling::FitMethod::Tolerance, .points = 1, .tolerance = 1.0, .max_pieces = 8}});
  } catch (const kccd::InputError& e) {
    kccd::fuzz::checkMessage(e.what(), path);
  }
  return 0;
}
