// GlContext on EGL without any surface: Mesa's surfaceless platform (EGL_MESA_platform_surfaceless;
// llvmpipe, or a GPU render node when Mesa has a driver for it), or with KCCD_EGL_DEVICE=N the N-th
// device of EGL_EXT_device_enumeration (EGL_EXT_platform_device: e.g. a GPU whose vendor EGL has
// no surfaceless platform). A configless compatibility-profile context, current with no surface;
// rendering goes to FBOs.
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <dlfcn.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "gl_api.hpp"
#include "gl_backends.hpp"

namespace kccd::render {
namespace {

std::string eglError(const char* call) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%s failed (EGL error 0x%04X)", call, static_cast<unsigned>(eglGetError()));
  return buf;
}

bool hasExtension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const std::size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n)
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  return false;
}

// EGL displays are per process and stay initialised until it exits: eglTerminate would unload
// Mesa's driver under the other contexts' feet (and with it the code that owns its allocations),
// and initialising an initialised display again does nothing.
std::mutex display_mutex;

// eglInitialize under the lock, for a context and for GlPreparation alike: one waits for the other.
bool initialiseDisplay(EGLDisplay display) {
  const std::lock_guard lock(display_mutex);
  EGLint major = 0, minor = 0;
  return eglInitialize(display, &major, &minor) == EGL_TRUE;
}

// The GL entry points of EGL contexts: eglGetProcAddress gives them all (EGL 1.5, or glvnd's
// dispatch to the current context); an EGL without EGL_KHR_get_all_proc_addresses has the core
// ones in glvnd's libOpenGL.
void* resolveGl(const char* name) {
  if (auto* found = eglGetProcAddress(name)) return reinterpret_cast<void*>(found);
  static void* const opengl = ::dlopen("libOpenGL.so.0", RTLD_NOW | RTLD_LOCAL);
  return opengl == nullptr ? nullptr : ::dlsym(opengl, name);
}

const detail::GlApi& eglGlApi() {
  static const std::pair<detail::GlApi, std::string> loaded = [] {
    std::pair<detail::GlApi, std::string> entry;
    entry.second = detail::loadGlApi(entry.first, resolveGl);
    return entry;
  }();
  if (!loaded.second.empty()) throw GlContextError("EGL: eglGetProcAddress gives no " + loaded.second);
  return loaded.first;
}

class EglContext final : public GlContext {
 public:
  EglContext() : GlContext(GlBackend::Egl) {
    const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (client == nullptr)
      throw GlContextError("EGL: no client extensions (libEGL without EGL 1.5 / EGL_EXT_client_extensions)");
    auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (get_display == nullptr) throw GlContextError("EGL: no eglGetPlatformDisplayEXT (EGL_EXT_platform_base)");
    std::string where;
    const char* device_env = std::getenv("KCCD_EGL_DEVICE");
    const bool want_device = device_env != nullptr && *device_env != '\0';
    if (want_device || !hasExtension(client, "EGL_MESA_platform_surfaceless")) {
      if (!hasExtension(client, "EGL_EXT_device_enumeration") || !hasExtension(client, "EGL_EXT_platform_device"))
        throw GlContextError(
            want_device
                ? "EGL: KCCD_EGL_DEVICE is set but EGL has no EGL_EXT_device_enumeration / EGL_EXT_platform_device"
                : "EGL: neither EGL_MESA_platform_surfaceless nor EGL_EXT_platform_device is available");
      auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
      EGLint count = 0;
      if (query_devices == nullptr || !query_devices(0, nullptr, &count) || count <= 0)
        throw GlContextError("EGL: no EGL device found (eglQueryDevicesEXT)");
      std::vector<EGLDeviceEXT> devices(static_cast<std::size_t>(count));
      query_devices(count, devices.data(), &count);
      int index = 0;
      if (want_device) {
        char* end = nullptr;
        const long v = std::strtol(device_env, &end, 10);
        if (*end != '\0' || v < 0 || v >= count)
          throw GlContextError("KCCD_EGL_DEVICE=" + std::string(device_env) + ": not a device index 0.." +
                               std::to_string(count - 1));
        index = static_cast<int>(v);
      }
      display_ = get_display(EGL_PLATFORM_DEVICE_EXT, devices[static_cast<std::size_t>(index)], nullptr);
      where = "EGL device " + std::to_string(index) + " of " + std::to_string(count);
    } else {
      display_ = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
      where = "EGL surfaceless";
    }
    if (display_ == EGL_NO_DISPLAY) throw GlContextError("EGL: " + where + ": " + eglError("eglGetPlatformDisplayEXT"));
    if (!initialiseDisplay(display_)) throw GlContextError("EGL: " + where + ": " + eglError("eglInitialize"));
    try {
      create(where);
    } catch (...) {
      release();
      throw;
    }
  }
  ~EglContext() override { release(); }

  void makeCurrent() override {
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
      throw GlContextError("EGL: " + eglError("eglMakeCurrent"));
    detail::setCurrentGlApi(api_);
  }

 private:
  void create(const std::string& where) {
    const char* ext = eglQueryString(display_, EGL_EXTENSIONS);
    if (!hasExtension(ext, "EGL_KHR_surfaceless_context"))
      throw GlContextError("EGL: " + where + " has no EGL_KHR_surfaceless_context");
    if (!eglBindAPI(EGL_OPENGL_API))
      throw GlContextError("EGL: " + where + ": desktop OpenGL: " + eglError("eglBindAPI"));
    EGLConfig config = EGL_NO_CONFIG_KHR;
    if (!hasExtension(ext, "EGL_KHR_no_config_context") && !hasExtension(ext, "EGL_MESA_configless_context")) {
      const EGLint want[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
      EGLint n = 0;
      if (!eglChooseConfig(display_, want, &config, 1, &n) || n < 1)
        throw GlContextError("EGL: " + where + ": no config for desktop OpenGL and no EGL_KHR_no_config_context");
    }
    // The renderer uses the fixed-function pipeline: a compatibility profile (Mesa gives its newest, 4.5 on llvmpipe).
    const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                              3,
                              EGL_CONTEXT_MINOR_VERSION,
                              0,
                              EGL_CONTEXT_OPENGL_PROFILE_MASK,
                              EGL_CONTEXT_OPENGL_COMPATIBILITY_PROFILE_BIT,
                              EGL_NONE};
    api_ = &eglGlApi();
    context_ = eglCreateContext(display_, config, EGL_NO_CONTEXT, attribs);
    if (context_ == EGL_NO_CONTEXT)
      throw GlContextError("EGL: " + where + ": a GL 3.0 compatibility context: " + eglError("eglCreateContext"));
    makeCurrent();
    describe("EGL", where);
  }

  void release() {
    if (display_ == EGL_NO_DISPLAY) return;
    if (context_ != EGL_NO_CONTEXT) {
      if (eglGetCurrentContext() == context_) {
        eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        detail::setCurrentGlApi(nullptr);
      }
      eglDestroyContext(display_, context_);
      context_ = EGL_NO_CONTEXT;
    }
    display_ = EGL_NO_DISPLAY;
  }

  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLContext context_ = EGL_NO_CONTEXT;
  const detail::GlApi* api_ = nullptr;
};

}  // namespace

std::unique_ptr<GlContext> detail::makeEglContext() { return std::make_unique<EglContext>(); }

void detail::initialiseEglDisplay() noexcept {
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!hasExtension(client, "EGL_MESA_platform_surfaceless")) return;
  auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (get_display == nullptr) return;
  const EGLDisplay display = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (display != EGL_NO_DISPLAY) (void)initialiseDisplay(display);
}

}  // namespace kccd::render
