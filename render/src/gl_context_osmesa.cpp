// GlContext on OSMesa (Mesa's llvmpipe, no display needed). Rendering goes to FBOs, so the
// OSMesa colour buffer is only a tiny placeholder that makes the context current.
#include <GL/gl.h>
#include <GL/osmesa.h>

#include <array>

#include "gl_backends.hpp"

namespace kccd::render {
namespace {

class OsMesaContext final : public GlContext {
 public:
  OsMesaContext() : GlContext(GlBackend::OsMesa) {
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
    ctx_ = OSMesaCreateContextAttribs(attribs, nullptr);
    if (ctx_ == nullptr) ctx_ = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr);
    if (ctx_ == nullptr)
      throw GlContextError("OSMesa: cannot create an off-screen GL context (OSMesaCreateContext failed)");
    try {
      makeCurrent();
      describe("OSMesa", "OSMesa");
    } catch (...) {
      OSMesaDestroyContext(ctx_);
      throw;
    }
  }
  ~OsMesaContext() override { OSMesaDestroyContext(ctx_); }

  void makeCurrent() override {
    if (!OSMesaMakeCurrent(ctx_, placeholder_.data(), GL_UNSIGNED_BYTE, 4, 4))
      throw GlContextError("OSMesa: OSMesaMakeCurrent failed");
  }

 private:
  OSMesaContext ctx_ = nullptr;
  std::array<unsigned char, 4 * 4 * 4> placeholder_{};
};

}  // namespace

std::unique_ptr<GlContext> detail::makeOsMesaContext() { return std::make_unique<OsMesaContext>(); }

}  // namespace kccd::render
