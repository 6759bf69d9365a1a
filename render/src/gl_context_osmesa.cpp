// GlContext on OSMesa (Mesa's llvmpipe, no display needed). Rendering goes to FBOs, so the
// OSMesa colour buffer is only a tiny placeholder that makes the context current.
#include <GL/osmesa.h>
#include <GL/gl.h>

#include <array>
#include <cstdio>

#include "kccd/render/gl_context.hpp"

namespace kccd::render {
namespace {

class OsMesaContext final : public GlContext {
 public:
  OsMesaContext() {
    const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_STENCIL_BITS, 0,
                           OSMESA_ACCUM_BITS, 0, OSMESA_PROFILE, OSMESA_COMPAT_PROFILE, 0};
    ctx_ = OSMesaCreateContextAttribs(attribs, nullptr);
    if (ctx_ == nullptr) ctx_ = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr);
    if (ctx_ == nullptr) throw GlContextError("OSMesa: cannot create an off-screen GL context (OSMesaCreateContext failed)");
    makeCurrent();
    const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    if (renderer == nullptr || version == nullptr) {
      OSMesaDestroyContext(ctx_);
      throw GlContextError(
          "OSMesa: the context gives no GL_RENDERER string (is libGL linked ahead of libOSMesa?)");
    }
    renderer_ = std::string(renderer) + " / " + version;
    int major = 0;
    if (std::sscanf(version, "%d", &major) != 1 || major < 3) {
      OSMesaDestroyContext(ctx_);
      throw GlContextError("OSMesa: GL " + std::string(version) + " is too old (framebuffer objects need 3.0)");
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

std::unique_ptr<GlContext> GlContext::make() { return std::make_unique<OsMesaContext>(); }

}  // namespace kccd::render
