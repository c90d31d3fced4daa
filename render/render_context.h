// A headless OpenGL context on OSMesa (Mesa's software rasterizer, llvmpipe).
//
// MuJoCo's renderer loads its GL entry points from whatever the process
// offers, trying EGL first, then OSMesa, then GLX: a process that renders must
// link libOSMesa and must not load libEGL. The context is a compatibility
// profile (MuJoCo 2.2.2 draws with the fixed-function pipeline) with 24 depth
// and 8 stencil bits. It draws into a small client-side window buffer; MuJoCo
// renders into its own offscreen framebuffer object, sized by the model.
//
// Threading: an OSMesa context is current per thread, and MuJoCo's GL function
// pointers are process-global: create and use every context of a process from
// one thread.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace vlab::render {

class GlContext {
 public:
  /// Creates a compatibility-profile OSMesa context and makes it current.
  /// Throws std::runtime_error when OSMesa cannot create or bind it.
  static std::unique_ptr<GlContext> Create();
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  /// Makes this context current on the calling thread (cheap when it already
  /// is). Throws std::runtime_error when OSMesa refuses.
  void MakeCurrent();

  /// "GL_RENDERER; GL_VERSION", e.g.
  /// "llvmpipe (LLVM 15.0.6, 256 bits); 4.5 (Compatibility Profile) Mesa 22.3.6".
  const std::string& description() const { return description_; }

 private:
  GlContext() = default;
  void* context_ = nullptr;           // OSMesaContext
  std::vector<std::uint8_t> window_;  // RGBA window buffer (unused by offscreen rendering)
  std::string description_;
};

}  // namespace vlab::render
