// Choosing the GlContext back end (KCCD_GL) and the checks every back end shares.
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>
#include <system_error>

#include "gl_api.hpp"
#include "gl_backends.hpp"
#include "kccd/render/gl_context.hpp"

namespace kccd::render {

const char* toString(GlBackend backend) { return backend == GlBackend::Egl ? "egl" : "osmesa"; }

bool compiledIn(GlBackend backend) {
  switch (backend) {
    case GlBackend::Egl:
#ifdef KCCD_HAVE_EGL
      return true;
#else
      return false;
#endif
    case GlBackend::OsMesa:
#ifdef KCCD_HAVE_OSMESA
      return true;
#else
      return false;
#endif
  }
  return false;
}

void GlContext::describe(const std::string& who, const std::string& suffix) {
  const auto* renderer = reinterpret_cast<const char*>(detail::GL().GetString(GL_RENDERER));
  const auto* version = reinterpret_cast<const char*>(detail::GL().GetString(GL_VERSION));
  if (renderer == nullptr || version == nullptr)
    throw GlContextError(who + ": the context gives no GL_RENDERER string (is libGL linked ahead of libOSMesa?)");
  int major = 0;
  if (std::sscanf(version, "%d", &major) != 1 || major < 3)
    throw GlContextError(who + ": GL " + std::string(version) + " is too old (framebuffer objects need 3.0)");
  renderer_ = std::string(renderer) + " / " + version + " / " + suffix;
}

std::unique_ptr<GlContext> GlContext::make(GlBackend backend) {
  if (!compiledIn(backend))
    throw GlContextError(std::string("KCCD_GL=") + toString(backend) + ": this build has no " +
                         (backend == GlBackend::Egl ? "EGL (pkg-config egl was not found)"
                                                    : "OSMesa (pkg-config osmesa was not found)"));
#ifdef KCCD_HAVE_EGL
  if (backend == GlBackend::Egl) return detail::makeEglContext();
#endif
#ifdef KCCD_HAVE_OSMESA
  if (backend == GlBackend::OsMesa) return detail::makeOsMesaContext();
#endif
  throw GlContextError("GL: no back end");
}

GlPreparation::GlPreparation() {
#ifdef KCCD_HAVE_EGL
  const char* env = std::getenv("KCCD_GL");
  const char* device = std::getenv("KCCD_EGL_DEVICE");
  if ((env != nullptr && *env != '\0' && std::string(env) != "egl") || (device != nullptr && *device != '\0')) return;
  try {
    thread_ = std::thread(detail::initialiseEglDisplay);
  } catch (const std::system_error&) {
    // No thread: make() loads the driver itself.
  }
#endif
}

GlPreparation::~GlPreparation() {
  if (thread_.joinable()) thread_.join();
}

namespace {
std::mutex& fallbackMutex() {
  static std::mutex m;
  return m;
}
std::string& fallbackReason() {
  static std::string reason;
  return reason;
}
}  // namespace

std::string GlContext::lastFallback() {
  const std::lock_guard lock(fallbackMutex());
  return fallbackReason();
}

std::unique_ptr<GlContext> GlContext::make() {
  const char* env = std::getenv("KCCD_GL");
  const std::string choice = env == nullptr ? "" : env;
  if (choice == "egl") return make(GlBackend::Egl);
  if (choice == "osmesa") return make(GlBackend::OsMesa);
  if (!choice.empty()) throw GlContextError("KCCD_GL=" + choice + ": unknown GL back end (use egl or osmesa)");
  // A chosen EGL device means EGL: its failure is reported, not hidden behind OSMesa.
  const char* device = std::getenv("KCCD_EGL_DEVICE");
  if (device != nullptr && *device != '\0') return make(GlBackend::Egl);
  // Unset: EGL first (the maintained path, and a GPU where Mesa or the EGL device has one), then OSMesa.
  std::string reasons;
  for (const GlBackend b : {GlBackend::Egl, GlBackend::OsMesa}) {
    if (!compiledIn(b)) continue;
    try {
      std::unique_ptr<GlContext> context = make(b);
      if (!reasons.empty()) {  // a fallback: kept, for the caller to say so
        const std::lock_guard lock(fallbackMutex());
        fallbackReason() = reasons;
      }
      return context;
    } catch (const GlContextError& e) {
      reasons += (reasons.empty() ? "" : "; ") + std::string(e.what());
    }
  }
  throw GlContextError("GL: no off-screen context (" +
                       (reasons.empty() ? std::string("no back end in this build") : reasons) + ")");
}

}  // namespace kccd::render
