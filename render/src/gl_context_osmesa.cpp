// GlContext on OSMesa (Mesa's llvmpipe, no display needed). Rendering goes to FBOs, so the
// OSMesa colour buffer is only a tiny placeholder that makes the context current. The library
// (KCCD_OSMESA_LIBRARY, with LLVM behind it) is loaded the first time an OSMesa context is made,
// so that the programs that never choose OSMesa do not load it at their start.
#include <GL/osmesa.h>
#include <dlfcn.h>

#include <array>
#include <mutex>
#include <string>
#include <type_traits>

#include "gl_api.hpp"
#include "gl_backends.hpp"

namespace kccd::render {
namespace {

struct OsMesaLibrary {
  decltype(&::OSMesaCreateContextAttribs) CreateContextAttribs = nullptr;
  decltype(&::OSMesaCreateContextExt) CreateContextExt = nullptr;
  decltype(&::OSMesaDestroyContext) DestroyContext = nullptr;
  decltype(&::OSMesaMakeCurrent) MakeCurrent = nullptr;
  decltype(&::OSMesaGetCurrentContext) GetCurrentContext = nullptr;
  decltype(&::OSMesaGetProcAddress) GetProcAddress = nullptr;
  detail::GlApi gl;
};

// Loaded once per process and never unloaded (contexts of other threads may live on); a failure
// is tried again at the next context.
const OsMesaLibrary& osMesaLibrary() {
  static std::mutex mutex;
  static OsMesaLibrary library;
  static bool loaded = false;
  const std::lock_guard lock(mutex);
  if (loaded) return library;
  void* handle = ::dlopen(KCCD_OSMESA_LIBRARY, RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* why = ::dlerror();
    throw GlContextError(std::string("OSMesa: cannot load " KCCD_OSMESA_LIBRARY " (") +
                         (why == nullptr ? "no reason given" : why) + ")");
  }
  OsMesaLibrary found;
  std::string missing;
  auto symbol = [&](auto& entry, const char* name) {
    entry = reinterpret_cast<std::remove_reference_t<decltype(entry)>>(::dlsym(handle, name));
    if (entry == nullptr && missing.empty()) missing = name;
  };
  symbol(found.CreateContextAttribs, "OSMesaCreateContextAttribs");
  symbol(found.CreateContextExt, "OSMesaCreateContextExt");
  symbol(found.DestroyContext, "OSMesaDestroyContext");
  symbol(found.MakeCurrent, "OSMesaMakeCurrent");
  symbol(found.GetCurrentContext, "OSMesaGetCurrentContext");
  symbol(found.GetProcAddress, "OSMesaGetProcAddress");
  if (missing.empty()) {
    static decltype(&::OSMesaGetProcAddress) get = nullptr;
    get = found.GetProcAddress;
    missing = detail::loadGlApi(found.gl, [](const char* name) { return reinterpret_cast<void*>(get(name)); });
  }
  if (!missing.empty()) throw GlContextError("OSMesa: " KCCD_OSMESA_LIBRARY " has no " + missing);
  library = found;
  loaded = true;
  return library;
}

class OsMesaContext final : public GlContext {
 public:
  OsMesaContext() : GlContext(GlBackend::OsMesa), lib_(osMesaLibrary()) {
    const int attribs[] = {OSMESA_FORMAT,
                           OSMESA_RGBA,
                           OSMESA_DEPTH_BITS,
                           24,
                           OSMESA_STENCIL_BITS,
                           0,
                           OSMESA_ACCUM_BITS,
                           0,
                           OSMESA_PROFILE,
                           OSMESA_COMPAT_PROFILE,
                           0};
    ctx_ = lib_.CreateContextAttribs(attribs, nullptr);
    if (ctx_ == nullptr) ctx_ = lib_.CreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr);
    if (ctx_ == nullptr)
      throw GlContextError("OSMesa: cannot create an off-screen GL context (OSMesaCreateContext failed)");
    try {
      makeCurrent();
      describe("OSMesa", "OSMesa");
    } catch (...) {
      destroy();
      throw;
    }
  }
  ~OsMesaContext() override { destroy(); }

  void makeCurrent() override {
    if (!lib_.MakeCurrent(ctx_, placeholder_.data(), GL_UNSIGNED_BYTE, 4, 4))
      throw GlContextError("OSMesa: OSMesaMakeCurrent failed");
    detail::setCurrentGlApi(&lib_.gl);
  }

 private:
  void destroy() {
    // As EGL's release: the thread's entry points are dropped with its current context.
    if (lib_.GetCurrentContext() == ctx_) detail::setCurrentGlApi(nullptr);
    lib_.DestroyContext(ctx_);
  }

  const OsMesaLibrary& lib_;
  OSMesaContext ctx_ = nullptr;
  std::array<unsigned char, 4 * 4 * 4> placeholder_{};
};

}  // namespace

std::unique_ptr<GlContext> detail::makeOsMesaContext() { return std::make_unique<OsMesaContext>(); }

}  // namespace kccd::render
