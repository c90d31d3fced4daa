// The parts `vlab export` (view_gltf.cc) assembles a .glb from, shared by its
// files: the binary buffer with its views and accessors, the triangles of a
// geom, the textured materials (view_gltf_texture.cc) and the cameras and
// lights (view_gltf_lights.cc). Internal to vlab_view.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <nlohmann/json.hpp>

namespace vlab::view::gltf {

inline constexpr int kFloat = 5126, kUint = 5125;                   // glTF componentType
inline constexpr int kArrayBuffer = 34962, kElementBuffer = 34963;  // bufferView targets

/// A geom's triangles in its own frame (m): x, y, z per vertex, three vertex
/// indices per triangle, counter-clockwise seen from outside. A box has 24
/// vertices and 12 triangles, face by face in MuJoCo's cube-texture order
/// (+x, -x, +y, -y, +z, -z): face f is indices [6 f, 6 f + 6).
struct Triangles {
  std::vector<float> positions;
  std::vector<std::uint32_t> indices;
};

/// The GLB's binary chunk and the JSON arrays that point into it.
class Buffer {
 public:
  /// Appends bytes (4-aligned) as a new bufferView; target 0: none. Returns its index.
  int Add(const void* data, std::size_t bytes, int target);
  /// A new accessor; min/max null: none. Returns its index.
  int Accessor(int view, int component, std::size_t count, const char* type, nlohmann::json min = nullptr,
               nlohmann::json max = nullptr);
  /// Floats as SCALAR/VEC2/VEC3/VEC4 of `components`, with min and max per component when `bounds`.
  int Floats(const std::vector<float>& v, int components, const char* type, int target, bool bounds);
  std::string& bin() { return bin_; }
  nlohmann::json& views() { return views_; }
  nlohmann::json& accessors() { return accessors_; }

 private:
  std::string bin_;
  nlohmann::json views_ = nlohmann::json::array(), accessors_ = nlohmann::json::array();
};

/// One primitive of a geom's mesh: its indices (into the geom's positions)
/// and its material.
struct Primitive {
  std::vector<std::uint32_t> indices;
  int material = -1;
};

/// A geom's look: texture coordinates (u, v per vertex; empty: untextured)
/// and its primitives with their materials.
struct Look {
  std::vector<float> uv;
  std::vector<Primitive> primitives;
};

/// The scene's textures as glTF images, samplers, textures and materials,
/// each image written once (a 2-D texture: one PNG; a cube texture: one PNG
/// per face, used by boxes only).
class Textures {
 public:
  /// `m`: the MJCF the recording was made with (null: no textures).
  Textures(const mjModel* m, Buffer* buffer) : m_(m), buffer_(buffer) {}
  /// The look of geom `g` (a scene.json geom) whose triangles are `t`
  /// (positions in the geom's frame; an ellipsoid's unit sphere is scaled by
  /// its size here). Throws InputError for a texture id the model lacks.
  Look LookOf(const nlohmann::json& g, const Triangles& t);
  void AddTo(nlohmann::json* gltf) const;
  int count() const { return static_cast<int>(textures_.size()); }

 private:
  int Material(const nlohmann::json& g, int texture);
  int Texture(int tex, int face);  // face -1: a 2-D texture
  const mjModel* m_;
  Buffer* buffer_;
  nlohmann::json images_ = nlohmann::json::array(), samplers_ = nlohmann::json::array(),
                 textures_ = nlohmann::json::array(), materials_ = nlohmann::json::array();
  std::map<std::pair<int, int>, int> texture_index_;  // (texture id, face) -> glTF texture
};

/// Where a camera or light of body `body` goes: the glTF node it hangs from
/// (-1: the scene's root) and its pose there.
struct Attachment {
  int parent = -1;
  double pos[3] = {0, 0, 0};
  double quat[4] = {1, 0, 0, 0};  ///< w, x, y, z
};

/// The MJCF's cameras (glTF perspective cameras) and lights
/// (KHR_lights_punctual) as nodes appended to `nodes`, children of their
/// bodies' nodes or roots (appended to `roots`). `recorded`: the recorded
/// bodies' model ids, in node order (node i is body recorded[i]). Returns
/// the number of cameras and lights placed; *skipped counts those on a body
/// that moves but is neither recorded nor welded to one that is.
struct CameraLightCounts {
  int cameras = 0, lights = 0, skipped = 0;
};
CameraLightCounts AddCamerasAndLights(const mjModel* m, const std::vector<int>& recorded, nlohmann::json* nodes,
                                      nlohmann::json* roots, nlohmann::json* gltf);

}  // namespace vlab::view::gltf
