// An off-screen OpenGL context behind a small interface: OSMesa today, EGL surfaceless later.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>

namespace kccd::render {

/// No usable GL context could be created (or it is not the one we need).
class GlContextError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// An off-screen GL context (compatibility profile, >= 3.0 with framebuffer objects) that is
/// current on the creating thread. Drawing goes to framebuffer objects, never to a window.
class GlContext {
 public:
  virtual ~GlContext() = default;
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  /// Makes the context current on the calling thread (one context per thread).
  virtual void makeCurrent() = 0;
  /// GL_RENDERER and GL_VERSION as reported at start-up, e.g. "llvmpipe (LLVM 15.0.6, 256 bits) / 4.5 ...".
  const std::string& renderer() const { return renderer_; }

  /// Creates the default off-screen context (OSMesa) and checks that it works: a renderer
  /// string, GL >= 3.0, framebuffer objects. Throws GlContextError with the reason otherwise.
  static std::unique_ptr<GlContext> make();

 protected:
  GlContext() = default;
  std::string renderer_;
};

}  // namespace kccd::render
