// libFuzzer target: camera files. Any input must load or be rejected with kccd::InputError
// (render::CameraError); any other exception, a crash, a hang or a sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <unistd.h>

#include "kccd/input_error.hpp"
#include "kccd/render/camera.hpp"

namespace {

// One temporary file per process, rewritten for every input (loadCamera reads a path).
const std::string& tempPath() {
  static const std::string path = [] {
    const char* dir = std::getenv("TMPDIR");
    std::string p = std::string(dir && *dir ? dir : "/tmp") + "/kccd_fuzz_camera_" + std::to_string(::getpid()) + ".yaml";
    return p;
  }();
  return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string& path = tempPath();
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  try {
    const kccd::render::Camera camera = kccd::render::loadCamera(path);
    camera.validate(path);  // a loaded camera is a valid one
  } catch (const kccd::InputError&) {
  }
  std::remove(path.c_str());
  return 0;
}
