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
#endif

}  // namespace kccd::render::detail
