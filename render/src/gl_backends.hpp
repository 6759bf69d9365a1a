// The back ends behind GlContext::make (internal).
#pragma once

#include <memory>

#include "kccd/render/gl_context.hpp"

namespace kccd::render::detail {

#ifdef KCCD_HAVE_OSMESA
std::unique_ptr<GlContext> makeOsMesaContext();
#endif
#ifdef KCCD_HAVE_EGL
std::unique_ptr<GlContext> makeEglContext();
/// Initialises EGL's surfaceless display (loading Mesa's driver) as a context would; errors ignored.
void initialiseEglDisplay() noexcept;
#endif

}  // namespace kccd::render::detail
