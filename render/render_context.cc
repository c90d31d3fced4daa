#include "render/render_context.h"

#include <GL/osmesa.h>

#include <stdexcept>

namespace vlab::render {

namespace {

// MuJoCo draws into its offscreen framebuffer; the window buffer only has to exist
constexpr int kWindowSize = 16;

std::string GlString(GLenum name) {
  const GLubyte* s = glGetString(name);
  return s ? reinterpret_cast<const char*>(s) : "unknown";
}

}  // namespace

std::unique_ptr<GlContext> GlContext::Create() {
  std::unique_ptr<GlContext> gl(new GlContext());
  // compatibility profile: a core profile lacks what MuJoCo 2.2.2 draws with
  OSMesaContext context = OSMesaCreateContextExt(OSMESA_RGBA, 24, 8, 0, nullptr);
  if (!context) throw std::runtime_error("OSMesa: cannot create a GL context (OSMesaCreateContextExt failed)");
  gl->context_ = context;
  gl->window_.assign(static_cast<std::size_t>(kWindowSize) * kWindowSize * 4, 0);
  gl->MakeCurrent();
  gl->description_ = GlString(GL_RENDERER) + "; " + GlString(GL_VERSION);
  return gl;
}

GlContext::~GlContext() {
  if (!context_) return;
  OSMesaContext context = static_cast<OSMesaContext>(context_);
  if (OSMesaGetCurrentContext() == context) OSMesaMakeCurrent(nullptr, nullptr, GL_UNSIGNED_BYTE, 0, 0);
  OSMesaDestroyContext(context);
}

void GlContext::MakeCurrent() {
  OSMesaContext context = static_cast<OSMesaContext>(context_);
  if (OSMesaGetCurrentContext() == context) return;
  if (!OSMesaMakeCurrent(context, window_.data(), GL_UNSIGNED_BYTE, kWindowSize, kWindowSize)) {
    throw std::runtime_error("OSMesa: cannot make the GL context current (OSMesaMakeCurrent failed)");
  }
}

}  // namespace vlab::render
