// libFuzzer target: camera files. Any input must load or be rejected with kccd::InputError
// (calib::CameraError); any other exception, a crash, a hang or a sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <unistd.h>

#include "fuzz_support.hpp"
#include "kccd/calib/camera.hpp"
#include "kccd/input_error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = kccd::fuzz::writeInput("fuzz_camera", "camera.yaml", data, size);
  try {
    const kccd::calib::Camera camera = kccd::calib::loadCamera(path);
    camera.validate(path);  // a loaded camera is a valid one
  } catch (const kccd::InputError& e) {
    kccd::fuzz::checkMessage(e.what(), path);
  }
  std::remove(path.c_str());
  return 0;
}
