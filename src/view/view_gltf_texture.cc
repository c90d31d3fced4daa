// `vlab export`'s materials and textures: texture coordinates that put a
// MuJoCo texture where MuJoCo 2.2.2's renderer puts it, and the texture's
// pixels as PNG images in the GLB's buffer.
#include <cmath>
#include <string>

#include "core/core_errors.h"
#include "render/image_codec.h"
#include "view/view_gltf_parts.h"

namespace vlab::view::gltf {

using nlohmann::json;

namespace {

constexpr int kRepeat = 10497, kClampToEdge = 33071;       // sampler wrap modes
constexpr int kLinear = 9729, kLinearMipmapLinear = 9987;  // sampler filters
constexpr int kTexture2d = mjTEXTURE_2D, kTextureCube = mjTEXTURE_CUBE;

// the half-sizes MuJoCo scales a primitive's unit shape by when it draws it
// (mjv_initGeom), from scene.json's size; a plane's zero size stays zero
void RenderSize(const json& g, double size[3]) {
  const std::string type = g["type"];
  const double s0 = g["size"][0], s1 = g["size"][1], s2 = g["size"][2];
  if (type == "sphere") {
    size[0] = size[1] = size[2] = s0;
  } else if (type == "capsule" || type == "cylinder") {
    size[0] = size[1] = s0;
    size[2] = s1;
  } else {
    size[0] = s0, size[1] = s1, size[2] = s2;
  }
}

// a 2-D texture: MuJoCo generates (s, t) from the object coordinates (GL_OBJECT_LINEAR:
// s = 0.5 scl_x x - 0.5, t = -0.5 scl_y y - 0.5 in the unit shape's frame, a plane's in metres)
// with scl = texrepeat, over the size unless texuniform (then per metre). In the geom's frame
// in metres that is scl_x = texrepeat_x / size_x (texuniform or a zero size: texrepeat_x).
// Row 0 of the image is t = 0, as v = 0 is in glTF: (u, v) = (s, t), repeating beyond [0, 1].
std::vector<float> PlanarUv(const json& g, const std::vector<float>& p_metres) {
  double size[3];
  RenderSize(g, size);
  const bool uniform = g.value("texuniform", false);
  double scale[2];
  for (int k = 0; k < 2; ++k) {
    const double repeat = g["texrepeat"][k];
    scale[k] = uniform || size[k] <= 0 ? repeat : repeat / size[k];
  }
  std::vector<float> uv;
  for (std::size_t i = 0; i + 2 < p_metres.size(); i += 3) {
    uv.push_back(static_cast<float>(0.5 * scale[0] * p_metres[i] - 0.5));
    uv.push_back(static_cast<float>(-0.5 * scale[1] * p_metres[i + 1] - 0.5));
  }
  return uv;
}

// a cube texture on a box: MuJoCo looks the cube map up by the direction of the object
// coordinates (texuniform: in metres, else in the unit box), OpenGL picks the face of the
// largest component and its (s, t) by the cube-map table (OpenGL 2.1, section 3.8.6). Row 0
// of a face is t = 0. Each face of the box is textured with its own face image, (u, v) = (s, t).
std::vector<float> CubeUv(const json& g, const std::vector<float>& p_metres) {
  double size[3];
  RenderSize(g, size);
  const bool uniform = g.value("texuniform", false);
  std::vector<float> uv;
  for (std::size_t v = 0; 3 * v + 2 < p_metres.size(); ++v) {
    double r[3];
    for (int k = 0; k < 3; ++k) r[k] = uniform ? p_metres[3 * v + k] : p_metres[3 * v + k] / size[k];
    const int face = static_cast<int>(v / 4);  // the box's vertices, 4 a face, in cube-texture order
    const double ma = std::abs(r[face / 2]);
    double sc = 0, tc = 0;
    switch (face) {
      case 0:  // +x
        sc = -r[2], tc = -r[1];
        break;
      case 1:  // -x
        sc = r[2], tc = -r[1];
        break;
      case 2:  // +y
        sc = r[0], tc = r[2];
        break;
      case 3:  // -y
        sc = r[0], tc = -r[2];
        break;
      case 4:  // +z
        sc = r[0], tc = -r[1];
        break;
      default:  // -z
        sc = -r[0], tc = -r[1];
        break;
    }
    uv.push_back(static_cast<float>(0.5 * (sc / ma + 1)));
    uv.push_back(static_cast<float>(0.5 * (tc / ma + 1)));
  }
  return uv;
}

}  // namespace

Look Textures::LookOf(const json& g, const Triangles& t) {
  Look look;
  const int tex = g.value("texture", -1);
  const std::string type = g["type"];
  const std::string name = g.value("name", "");
  if (tex >= 0 && (!m_ || tex >= m_->ntex)) {
    throw InputError("vlab export: geom '" + name + "': texture " + std::to_string(tex) +
                     " is not in the model (give the MJCF the run was recorded with: --model)");
  }
  std::vector<float> p = t.positions;
  if (type == "ellipsoid") {
    for (std::size_t i = 0; i < p.size(); ++i) p[i] *= g["size"][i % 3].get<float>();
  }
  const int kind = tex >= 0 ? m_->tex_type[tex] : -1;
  if (kind == kTexture2d && type != "mesh") {
    look.uv = PlanarUv(g, p);
    look.primitives.push_back({t.indices, Material(g, Texture(tex, -1))});
  } else if (kind == kTextureCube && type == "box") {
    look.uv = CubeUv(g, p);
    for (int f = 0; f < 6; ++f) {
      look.primitives.push_back(
          {{t.indices.begin() + 6 * f, t.indices.begin() + 6 * f + 6}, Material(g, Texture(tex, f))});
    }
  } else {
    look.primitives.push_back({t.indices, Material(g, -1)});
  }
  return look;
}

int Textures::Material(const json& g, int texture) {
  const json& c = g["rgba"];
  json pbr = {{"baseColorFactor", {c[0], c[1], c[2], c[3]}}, {"metallicFactor", 0.0}, {"roughnessFactor", 0.8}};
  if (texture >= 0) pbr["baseColorTexture"] = {{"index", texture}};
  json material = {{"name", g.value("name", "")}, {"pbrMetallicRoughness", pbr}, {"doubleSided", g["type"] == "plane"}};
  if (c[3].get<double>() < 1) material["alphaMode"] = "BLEND";
  materials_.push_back(material);
  return static_cast<int>(materials_.size()) - 1;
}

int Textures::Texture(int tex, int face) {
  const auto found = texture_index_.find({tex, face});
  if (found != texture_index_.end()) return found->second;
  // the pixels: MuJoCo's RGB rows top-down; a cube texture's six square faces stacked
  const int w = m_->tex_width[tex], h = face < 0 ? m_->tex_height[tex] : w;
  const mjtByte* pixels = m_->tex_rgb + m_->tex_adr[tex] + (face < 0 ? 0 : 3L * w * w * face);
  std::vector<std::uint8_t> png;
  render::EncodePng({w, h, 3, 8, pixels, 0}, -1, &png);
  const char* name = mj_id2name(m_, mjOBJ_TEXTURE, tex);
  static const char* const kFaces[] = {"+x", "-x", "+y", "-y", "+z", "-z"};
  std::string label = name ? name : "texture " + std::to_string(tex);
  if (face >= 0) label += std::string(" ") + kFaces[face];
  images_.push_back(
      {{"name", label}, {"bufferView", buffer_->Add(png.data(), png.size(), 0)}, {"mimeType", "image/png"}});
  // 2-D textures repeat (GL_REPEAT), cube faces end at their edges (a cube map clamps)
  const int wrap = face < 0 ? kRepeat : kClampToEdge;
  int sampler = -1;
  for (std::size_t i = 0; i < samplers_.size(); ++i) {
    if (samplers_[i]["wrapS"] == wrap) sampler = static_cast<int>(i);
  }
  if (sampler < 0) {
    samplers_.push_back({{"magFilter", kLinear}, {"minFilter", kLinearMipmapLinear}, {"wrapS", wrap}, {"wrapT", wrap}});
    sampler = static_cast<int>(samplers_.size()) - 1;
  }
  textures_.push_back({{"name", label}, {"sampler", sampler}, {"source", images_.size() - 1}});
  texture_index_[{tex, face}] = static_cast<int>(textures_.size()) - 1;
  return texture_index_[{tex, face}];
}

void Textures::AddTo(json* gltf) const {
  (*gltf)["materials"] = materials_;
  if (textures_.empty()) return;
  (*gltf)["images"] = images_;
  (*gltf)["samplers"] = samplers_;
  (*gltf)["textures"] = textures_;
}

}  // namespace vlab::view::gltf
