#include "gl_targets.hpp"

#include <algorithm>
#include <string>

#include "gl_api.hpp"
#include "kccd/render/gl_context.hpp"

namespace kccd::render::detail {
namespace {

// Labels are drawn by a shader into a one-channel 8-bit target (label / 255, exact in unorm8),
// depth-tested so each pixel keeps the label of the nearest surface whatever the drawing order.
// The depth written is reversed, near / (camera z) in (0, 1] (GL_GREATER, cleared to 0): in the
// float depth buffer it tells surfaces apart to ~1e-7 of their distance whatever the near plane
// (which a volume next to the camera, even outside the view, pulls in close; a conventional
// depth buffer would resolve ~6e-8 z^2 / near). The colour output is unused (that draw buffer
// is off), so the colour layer is drawn afterwards exactly as without labels.
constexpr const char* kLabelVertexShader = R"(#version 330 compatibility
out float camera_z;
void main() {
  gl_Position = ftransform();
  camera_z = gl_Vertex.z;
}
)";
constexpr const char* kLabelFragmentShader = R"(#version 330 compatibility
in float camera_z;
uniform uint label;
uniform float near;
layout(location = 0) out vec4 colour;
layout(location = 1) out vec4 nearest;
void main() {
  colour = vec4(0.0);
  nearest = vec4(float(label) / 255.0, 0.0, 0.0, 0.0);
  gl_FragDepth = near / max(camera_z, near);
}
)";

GLuint compile(GLenum type, const char* source) {
  const GLuint shader = GL().CreateShader(type);
  GL().ShaderSource(shader, 1, &source, nullptr);
  GL().CompileShader(shader);
  GLint ok = 0;
  GL().GetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[1024] = {};
    GL().GetShaderInfoLog(shader, sizeof log, nullptr, log);
    GL().DeleteShader(shader);
    throw GlContextError(std::string("GL: label shader: ") + log);
  }
  return shader;
}

void check(GLuint fbo, const char* what) {
  GL().BindFramebuffer(GL_FRAMEBUFFER, fbo);
  const GLenum status = GL().CheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    throw GlContextError(std::string("GL: ") + what + " framebuffer incomplete (status " + std::to_string(status) +
                         ")");
}

GLuint renderbuffer(GLenum format, int samples, int w, int h) {
  GLuint rb = 0;
  GL().GenRenderbuffers(1, &rb);
  GL().BindRenderbuffer(GL_RENDERBUFFER, rb);
  if (samples > 1)
    GL().RenderbufferStorageMultisample(GL_RENDERBUFFER, samples, format, w, h);
  else
    GL().RenderbufferStorage(GL_RENDERBUFFER, format, w, h);
  return rb;
}

}  // namespace

GlTargets::GlTargets(int w, int h, int want_samples, int mw, int mh)
    : width(w), height(h), mask_width(mw), mask_height(mh) {
  GLint max_samples = 0, max_size = 0;
  GL().GetIntegerv(GL_MAX_SAMPLES, &max_samples);
  GL().GetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_size);
  if (std::max({w, h, mw, mh}) > max_size)
    throw GlContextError("GL: image " + std::to_string(std::max(w, mw)) + "x" + std::to_string(std::max(h, mh)) +
                         " exceeds the renderbuffer limit " + std::to_string(max_size));
  samples = want_samples > 1 ? std::min(want_samples, static_cast<int>(max_samples)) : 0;
  resolve_colour = renderbuffer(GL_RGBA8, 0, w, h);
  GL().GenFramebuffers(1, &resolve_fbo);
  GL().BindFramebuffer(GL_FRAMEBUFFER, resolve_fbo);
  GL().FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, resolve_colour);
  resolve_depth = renderbuffer(GL_DEPTH_COMPONENT32F, 0, w, h);  // float: labels of near surfaces at any near plane
  GL().FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, resolve_depth);
  resolve_labels = renderbuffer(GL_R8, 0, w, h);
  GL().FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_RENDERBUFFER, resolve_labels);
  check(resolve_fbo, "colour");
  if (samples > 1) {
    ms_colour = renderbuffer(GL_RGBA8, samples, w, h);
    GL().GenFramebuffers(1, &ms_fbo);
    GL().BindFramebuffer(GL_FRAMEBUFFER, ms_fbo);
    GL().FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, ms_colour);
    ms_depth = renderbuffer(GL_DEPTH_COMPONENT24, samples, w, h);
    GL().FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, ms_depth);
    check(ms_fbo, "multisample colour");
  }
  if (mw != w || mh != h) {
    mask_labels = renderbuffer(GL_R8, 0, mw, mh);
    GL().GenFramebuffers(1, &mask_fbo);
    GL().BindFramebuffer(GL_FRAMEBUFFER, mask_fbo);
    GL().FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_RENDERBUFFER, mask_labels);
    mask_depth = renderbuffer(GL_DEPTH_COMPONENT32F, 0, mw, mh);
    GL().FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, mask_depth);
    const GLenum buffers[] = {GL_NONE, GL_COLOR_ATTACHMENT1};
    GL().DrawBuffers(2, buffers);
    GL().ReadBuffer(GL_COLOR_ATTACHMENT1);
    check(mask_fbo, "mask");
  }
  GL().BindFramebuffer(GL_FRAMEBUFFER, 0);
  const GLuint vs = compile(GL_VERTEX_SHADER, kLabelVertexShader);
  const GLuint fs = compile(GL_FRAGMENT_SHADER, kLabelFragmentShader);
  program = GL().CreateProgram();
  GL().AttachShader(program, vs);
  GL().AttachShader(program, fs);
  GL().LinkProgram(program);
  GL().DeleteShader(vs);
  GL().DeleteShader(fs);
  GLint ok = 0;
  GL().GetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[1024] = {};
    GL().GetProgramInfoLog(program, sizeof log, nullptr, log);
    GL().DeleteProgram(program);
    throw GlContextError(std::string("GL: label shader: ") + log);
  }
  label_location = GL().GetUniformLocation(program, "label");
  near_location = GL().GetUniformLocation(program, "near");
}

GlTargets::~GlTargets() {
  const GLuint fbos[] = {ms_fbo, resolve_fbo, mask_fbo};
  const GLuint rbs[] = {ms_colour, resolve_colour, resolve_labels, mask_labels, ms_depth, resolve_depth, mask_depth};
  GL().DeleteFramebuffers(3, fbos);
  GL().DeleteRenderbuffers(7, rbs);
  GL().DeleteProgram(program);
}

}  // namespace kccd::render::detail
