#include "gl_api.hpp"

namespace kccd::render::detail {
namespace {
thread_local const GlApi* current_api = nullptr;
}  // namespace

std::string loadGlApi(GlApi& api, void* (*resolve)(const char* name)) {
  std::string missing;
#define KCCD_GL_LOAD(name)                                              \
  api.name = reinterpret_cast<decltype(api.name)>(resolve("gl" #name)); \
  if (api.name == nullptr && missing.empty()) missing = "gl" #name;
  KCCD_GL_FUNCTIONS(KCCD_GL_LOAD)
#undef KCCD_GL_LOAD
  return missing;
}

const GlApi& GL() noexcept { return *current_api; }

void setCurrentGlApi(const GlApi* api) noexcept { current_api = api; }

}  // namespace kccd::render::detail
