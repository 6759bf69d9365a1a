// The renderer's GL targets (internal): the framebuffers a frame is drawn into and read back
// from, and the shader that writes mask labels. Made and used with the renderer's context current.
#pragma once

#include <GL/gl.h>

namespace kccd::render::detail {

/// The framebuffers: a multisampled colour target resolved into a plain one, with a second
/// attachment for labels (drawn in the colour pass, or alone for a mask only), and a label target
/// of its own when the mask uses another pinhole scale than the colour layer; and the label shader.
class GlTargets {
 public:
  /// Targets of w x h (colour) and mw x mh (mask) pixels, multisampled up to `want_samples`
  /// (0 or 1: not); throws GlContextError when this GL cannot make them.
  GlTargets(int w, int h, int want_samples, int mw, int mh);
  ~GlTargets();
  GlTargets(const GlTargets&) = delete;
  GlTargets& operator=(const GlTargets&) = delete;

  GLuint ms_fbo = 0, ms_colour = 0;
  GLuint resolve_fbo = 0, resolve_colour = 0, resolve_labels = 0;
  GLuint ms_depth = 0, resolve_depth = 0;                // depth for the shaded (opaque) look
  GLuint mask_fbo = 0, mask_labels = 0, mask_depth = 0;  // only with a separate mask scale
  GLuint program = 0;                                    // the label shader
  GLint label_location = -1, near_location = -1;         // its uniforms
  int samples = 0;
  int width = 0, height = 0;
  int mask_width = 0, mask_height = 0;
};

}  // namespace kccd::render::detail
