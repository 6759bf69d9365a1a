// An off-screen OpenGL context behind a small interface, on one of two back ends: EGL
// surfaceless (Mesa's EGL_MESA_platform_surfaceless, or an EGL device) and OSMesa.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

namespace kccd::render {

/// No usable GL context could be created (or it is not the one we need).
class GlContextError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The library a GlContext is made with.
enum class GlBackend {
  Egl,     ///< EGL without a window: Mesa's surfaceless platform, or an EGL device (KCCD_EGL_DEVICE)
  OsMesa,  ///< Mesa's OSMesa (removed from Mesa 25.1 onward)
};
/// "egl" or "osmesa" (the values of KCCD_GL).
const char* toString(GlBackend backend);
/// Whether this build has the back end at all (its library was found at configure time).
bool compiledIn(GlBackend backend);

/// An off-screen GL context (compatibility profile, >= 3.0 with framebuffer objects) that is
/// current on the creating thread. Drawing goes to framebuffer objects, never to a window.
class GlContext {
 public:
  virtual ~GlContext() = default;
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  /// Makes the context current on the calling thread (one context per thread).
  virtual void makeCurrent() = 0;
  /// GL_RENDERER and GL_VERSION as reported at start-up and the back end, e.g.
  /// "llvmpipe (LLVM 15.0.6, 256 bits) / 4.5 (Compatibility Profile) Mesa 22.3.6 / EGL surfaceless".
  const std::string& renderer() const { return renderer_; }
  GlBackend backend() const { return backend_; }

  /// Creates the off-screen context chosen by the environment variable KCCD_GL: "egl" or
  /// "osmesa" (only that one, an error if it does not work); unset or empty: EGL, and OSMesa
  /// when EGL gives no context. Checks that it works: a renderer string, GL >= 3.0, framebuffer
  /// objects. Throws GlContextError with a one-line reason otherwise.
  static std::unique_ptr<GlContext> make();
  /// Creates a context on the given back end (KCCD_GL is not read).
  static std::unique_ptr<GlContext> make(GlBackend backend);
  /// Why make() last fell back from EGL to OSMesa in this process ("" if it never did): the
  /// rendered bytes may then differ from EGL's, and the renderer string does. Thread-safe.
  static std::string lastFallback();

 protected:
  explicit GlContext(GlBackend backend) : backend_(backend) {}
  /// Reads GL_RENDERER and GL_VERSION of the current context into renderer_ (with `suffix`
  /// appended); throws GlContextError (prefixed with `who`) when missing or older than 3.0.
  void describe(const std::string& who, const std::string& suffix);
  std::string renderer_;

 private:
  GlBackend backend_;
};

/// Loads GlContext::make()'s first choice (EGL's surfaceless display, and with it Mesa's driver)
/// on a thread of its own while it lives, so that contexts made after other set-up find the
/// driver loaded; a make() that comes first waits for the load. The destructor waits for the load
/// to end (so no exit overtakes it). Does nothing for OSMesa or an EGL device (KCCD_GL,
/// KCCD_EGL_DEVICE) or without EGL; errors are left to make().
class GlPreparation {
 public:
  GlPreparation();
  ~GlPreparation();
  GlPreparation(const GlPreparation&) = delete;
  GlPreparation& operator=(const GlPreparation&) = delete;

 private:
  std::thread thread_;
};

}  // namespace kccd::render
