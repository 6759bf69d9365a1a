// The GL entry points the renderer calls, resolved for each context by its back end (internal).
// No GL library is linked: under EGL they come from eglGetProcAddress, under OSMesa from the
// OSMesa library loaded only when that back end is chosen (with LLVM, a fifth of a start-up).
#pragma once

#include <GL/gl.h>
#include <GL/glext.h>

#include <string>

// Every gl* function the renderer calls, without its prefix.
// clang-format off
#define KCCD_GL_FUNCTIONS(X)                                                                                           \
  X(AttachShader) X(BindFramebuffer) X(BindRenderbuffer) X(BlendFunc) X(BlendFuncSeparate) X(BlitFramebuffer)          \
  X(CheckFramebufferStatus) X(Clear) X(ClearBufferfv) X(ClearColor) X(ClearDepth) X(Color4d) X(Color4f)                \
  X(ColorPointer) X(CompileShader) X(CreateProgram) X(CreateShader) X(CullFace) X(DeleteFramebuffers)                  \
  X(DeleteProgram) X(DeleteRenderbuffers) X(DeleteShader) X(DepthFunc) X(DepthMask) X(Disable)                         \
  X(DisableClientState) X(DrawArrays) X(DrawBuffers) X(DrawElements) X(Enable) X(EnableClientState) X(Finish)          \
  X(FramebufferRenderbuffer) X(FrontFace) X(GenFramebuffers) X(GenRenderbuffers) X(GetIntegerv)                        \
  X(GetProgramInfoLog) X(GetProgramiv) X(GetShaderInfoLog) X(GetShaderiv) X(GetString) X(GetUniformLocation) X(Hint)   \
  X(LineWidth) X(LinkProgram) X(LoadIdentity) X(LoadMatrixf) X(MatrixMode) X(PixelStorei) X(PopMatrix)                 \
  X(PushMatrix) X(ReadBuffer) X(ReadPixels) X(RenderbufferStorage) X(RenderbufferStorageMultisample) X(Scissor)        \
  X(ShadeModel) X(ShaderSource) X(Uniform1f) X(Uniform1ui) X(UseProgram) X(VertexPointer) X(Viewport)
// clang-format on

namespace kccd::render::detail {

/// One context's GL entry points: member Clear is glClear, and so on (types from the GL headers).
struct GlApi {
#define KCCD_GL_MEMBER(name) decltype(&::gl##name) name = nullptr;  // NOLINT(bugprone-macro-parentheses): a name
  KCCD_GL_FUNCTIONS(KCCD_GL_MEMBER)
#undef KCCD_GL_MEMBER
};

/// Fills every entry through resolve ("glClear" → its address); returns the first name it could not
/// resolve, empty when all were found.
std::string loadGlApi(GlApi& api, void* (*resolve)(const char* name));

/// The entry points of the context current on the calling thread (precondition: a GlContext made
/// current on this thread, which sets them).
const GlApi& GL() noexcept;

/// Makes api the calling thread's entry points (nullptr: none, after its context was released).
void setCurrentGlApi(const GlApi* api) noexcept;

}  // namespace kccd::render::detail
