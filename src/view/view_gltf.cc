#include "view/view_gltf.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/core_errors.h"
#include "scene/scene_geometry.h"
#include "view/view_gltf_parts.h"
#include "view/view_model.h"

namespace vlab::view {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using gltf::kArrayBuffer;
using gltf::kElementBuffer;
using gltf::kFloat;
using gltf::kUint;
using gltf::Triangles;

// a surface of revolution about z from a profile of (radius, z) points
Triangles Lathe(const std::vector<std::pair<double, double>>& profile, int segments) {
  Triangles t;
  for (const auto& [r, z] : profile) {
    for (int s = 0; s <= segments; ++s) {
      const double a = 2 * M_PI * s / segments;
      t.positions.insert(t.positions.end(), {static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a)),
                                             static_cast<float>(z)});
    }
  }
  const std::uint32_t row = static_cast<std::uint32_t>(segments + 1);
  for (std::uint32_t i = 0; i + 1 < profile.size(); ++i) {
    for (std::uint32_t s = 0; s < static_cast<std::uint32_t>(segments); ++s) {
      const std::uint32_t a = i * row + s, b = a + 1, c = a + row, d = c + 1;  // counter-clockwise seen from outside
      t.indices.insert(t.indices.end(), {a, b, d, a, d, c});
    }
  }
  return t;
}

std::vector<std::pair<double, double>> Arc(double r, double z0, double from, double to, int n) {
  std::vector<std::pair<double, double>> p;
  for (int i = 0; i <= n; ++i) {
    const double a = from + (to - from) * i / n;
    p.push_back({r * std::cos(a), z0 + r * std::sin(a)});
  }
  return p;
}

Triangles Box(double x, double y, double z) {
  Triangles t;
  // each face: normal axis n, sign; four corners counter-clockwise seen from outside
  const double h[3] = {x, y, z};
  for (int n = 0; n < 3; ++n) {
    for (int sign : {1, -1}) {
      const int u = (n + 1) % 3, v = (n + 2) % 3;
      const std::uint32_t base = static_cast<std::uint32_t>(t.positions.size() / 3);
      const double corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
      for (const auto& c : corners) {
        double p[3];
        p[n] = sign * h[n];
        p[u] = c[0] * h[u] * sign;
        p[v] = c[1] * h[v];
        t.positions.insert(t.positions.end(),
                           {static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2])});
      }
      t.indices.insert(t.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    }
  }
  return t;
}

// the triangles of a geom in its own frame (ellipsoid: a unit sphere, scaled by its node)
Triangles GeomTriangles(const json& g, const ViewModel* model) {
  const std::string type = g["type"];
  const double s0 = g["size"][0], s1 = g["size"][1], s2 = g["size"][2];
  if (type == "box") return Box(s0, s1, s2);
  if (type == "sphere") return Lathe(Arc(s0, 0, -M_PI / 2, M_PI / 2, 16), 32);
  if (type == "ellipsoid") return Lathe(Arc(1, 0, -M_PI / 2, M_PI / 2, 16), 32);
  if (type == "cylinder") return Lathe({{0, -s1}, {s0, -s1}, {s0, s1}, {0, s1}}, 32);
  if (type == "capsule") {
    auto p = Arc(s0, -s1, -M_PI / 2, 0, 8);
    const auto top = Arc(s0, s1, 0, M_PI / 2, 8);
    p.insert(p.end(), top.begin(), top.end());
    return Lathe(p, 32);
  }
  if (type == "plane") {
    const float x = static_cast<float>(s0 > 0 ? s0 : 10), y = static_cast<float>(s1 > 0 ? s1 : 10);
    return {{-x, -y, 0, x, -y, 0, x, y, 0, -x, y, 0}, {0, 1, 2, 0, 2, 3}};
  }
  Triangles t;
  if (type == "mesh" && model) {
    std::string bytes;
    if (!model->MeshBytes(g["mesh"].get<int>(), &bytes)) return t;
    std::uint32_t counts[2];
    std::memcpy(counts, bytes.data(), 8);
    t.positions.resize(3 * counts[0]);
    t.indices.resize(3 * counts[1]);
    std::memcpy(t.positions.data(), bytes.data() + 8, 12 * counts[0]);
    std::memcpy(t.indices.data(), bytes.data() + 8 + 12 * counts[0], 12 * counts[1]);
  }
  return t;
}

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("vlab export: cannot read '" + path.string() + "'");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void PutU32(std::string* out, std::uint32_t v) { out->append(reinterpret_cast<const char*>(&v), 4); }

}  // namespace

int gltf::Buffer::Add(const void* data, std::size_t bytes, int target) {
  while (bin_.size() % 4) bin_.push_back(0);
  json view = {{"buffer", 0}, {"byteOffset", bin_.size()}, {"byteLength", bytes}};
  if (target) view["target"] = target;
  bin_.insert(bin_.end(), static_cast<const char*>(data), static_cast<const char*>(data) + bytes);
  views_.push_back(view);
  return static_cast<int>(views_.size()) - 1;
}

int gltf::Buffer::Accessor(int view, int component, std::size_t count, const char* type, json min, json max) {
  json a = {{"bufferView", view}, {"componentType", component}, {"count", count}, {"type", type}};
  if (!min.is_null()) a["min"] = min;
  if (!max.is_null()) a["max"] = max;
  accessors_.push_back(a);
  return static_cast<int>(accessors_.size()) - 1;
}

int gltf::Buffer::Floats(const std::vector<float>& v, int components, const char* type, int target, bool bounds) {
  const int view = Add(v.data(), 4 * v.size(), target);
  json min = nullptr, max = nullptr;
  if (bounds) {
    min = json::array();
    max = json::array();
    for (int c = 0; c < components; ++c) {
      float lo = INFINITY, hi = -INFINITY;
      for (std::size_t i = c; i < v.size(); i += components) lo = std::min(lo, v[i]), hi = std::max(hi, v[i]);
      min.push_back(lo);
      max.push_back(hi);
    }
  }
  return Accessor(view, kFloat, v.size() / components, type, min, max);
}

GltfSummary ExportGltf(const std::string& run_dir, const std::string& glb_path, const std::string& model_path) {
  if (fs::exists(glb_path))
    throw InputError("vlab export: '" + glb_path + "' exists: it is not overwritten (remove it first)");
  const fs::path scene_path = fs::path(run_dir) / "scene.json", poses_path = fs::path(run_dir) / "poses.bin";
  const json info = json::parse(ReadFile(scene_path), nullptr, false);
  if (info.is_discarded() || !info.contains("bodies") || !info.contains("geoms")) {
    throw InputError("vlab export: '" + scene_path.string() + "' is not a scene description (outputs: {poses: ...})");
  }
  const std::string poses = ReadFile(poses_path);
  const std::size_t bodies = info["bodies"].size(), frame_bytes = 16 + 28 * bodies;
  if (poses.empty() || poses.size() % frame_bytes != 0) {
    throw InputError("vlab export: '" + poses_path.string() + "' is not whole frames of " + std::to_string(bodies) +
                     " bodies");
  }
  const long frames = static_cast<long>(poses.size() / frame_bytes);
  // the MJCF: needed for meshes and textures, used for cameras and lights where it is found
  std::unique_ptr<ViewModel> model;
  const bool needs_model = std::any_of(info["geoms"].begin(), info["geoms"].end(), [](const json& g) {
    return g["type"] == "mesh" || g.value("texture", -1) >= 0;
  });
  const std::string mjcf = model_path.empty() ? info.value("model", std::string()) : model_path;
  if (needs_model || !model_path.empty() || (!mjcf.empty() && fs::is_regular_file(mjcf))) {
    model = ViewModel::Load(mjcf);
    if (scene::SceneGeometry(model->model(), scene::SceneBodies(model->model()))["bodies"] != info["bodies"]) {
      throw InputError("vlab export: the model '" + mjcf + "' is not the one '" + scene_path.string() +
                       "' was recorded with (its bodies differ; give that MJCF with --model)");
    }
  }
  const mjModel* m = model ? model->model() : nullptr;

  // times and each body's translations and rotations (glTF quaternions are x, y, z, w)
  std::vector<float> times(frames);
  std::vector<std::vector<float>> translation(bodies), rotation(bodies);
  for (long k = 0; k < frames; ++k) {
    const char* f = poses.data() + k * frame_bytes;
    double t = 0;
    std::memcpy(&t, f, 8);
    times[k] = static_cast<float>(t);
    for (std::size_t b = 0; b < bodies; ++b) {
      float p[7];
      std::memcpy(p, f + 16 + 28 * b, 28);
      translation[b].insert(translation[b].end(), {p[0], p[1], p[2]});
      rotation[b].insert(rotation[b].end(), {p[4], p[5], p[6], p[3]});
    }
  }

  gltf::Buffer buffer;
  gltf::Textures textures(m, &buffer);
  json nodes = json::array(), meshes_json = json::array(), roots = json::array();
  for (std::size_t b = 0; b < bodies; ++b) {
    const std::vector<float>& tr = translation[b];
    const std::vector<float>& ro = rotation[b];
    nodes.push_back({{"name", info["bodies"][b]},
                     {"translation", {tr[0], tr[1], tr[2]}},
                     {"rotation", {ro[0], ro[1], ro[2], ro[3]}},
                     {"children", json::array()}});
    roots.push_back(b);
  }
  int geoms = 0;
  json gltf_extra = json::object();  // cameras, lights
  for (const json& g : info["geoms"]) {
    const Triangles t = GeomTriangles(g, model.get());
    if (t.indices.empty()) continue;
    const gltf::Look look = textures.LookOf(g, t);
    json attributes = {{"POSITION", buffer.Floats(t.positions, 3, "VEC3", kArrayBuffer, true)}};
    if (!look.uv.empty()) attributes["TEXCOORD_0"] = buffer.Floats(look.uv, 2, "VEC2", kArrayBuffer, false);
    json primitives = json::array();
    for (const gltf::Primitive& p : look.primitives) {
      const int view = buffer.Add(p.indices.data(), 4 * p.indices.size(), kElementBuffer);
      const auto [low, high] = std::minmax_element(p.indices.begin(), p.indices.end());
      const int index = buffer.Accessor(view, kUint, p.indices.size(), "SCALAR", {*low}, {*high});
      primitives.push_back({{"attributes", attributes}, {"indices", index}, {"material", p.material}});
    }
    meshes_json.push_back({{"name", g.value("name", "")}, {"primitives", primitives}});
    json node = {{"name", g.value("name", "")},
                 {"mesh", meshes_json.size() - 1},
                 {"translation", g["pos"]},
                 {"rotation", {g["quat"][1], g["quat"][2], g["quat"][3], g["quat"][0]}}};
    if (g["type"] == "ellipsoid") node["scale"] = g["size"];
    nodes.push_back(node);
    const int body = g["body"];
    if (body >= 0)
      nodes[body]["children"].push_back(nodes.size() - 1);
    else
      roots.push_back(nodes.size() - 1);
    ++geoms;
  }
  std::vector<int> recorded;
  if (m) recorded = scene::SceneBodies(m);
  const gltf::CameraLightCounts placed = gltf::AddCamerasAndLights(m, recorded, &nodes, &roots, &gltf_extra);
  for (json& n : nodes) {
    if (n.contains("children") && n["children"].empty()) n.erase("children");
  }
  // the animation: one input (times), two outputs per body
  const int input = buffer.Floats(times, 1, "SCALAR", 0, true);
  json samplers = json::array(), channels = json::array();
  for (std::size_t b = 0; b < bodies; ++b) {
    for (const auto& [path, values, type, n] :
         {std::tuple{"translation", &translation[b], "VEC3", 3}, std::tuple{"rotation", &rotation[b], "VEC4", 4}}) {
      const int output = buffer.Floats(*values, n, type, 0, false);
      samplers.push_back({{"input", input}, {"output", output}, {"interpolation", "LINEAR"}});
      channels.push_back({{"sampler", samplers.size() - 1}, {"target", {{"node", b}, {"path", path}}}});
    }
  }
  json gltf = {{"asset", {{"version", "2.0"}, {"generator", "vlab export"}}},
               {"scene", 0},
               {"scenes", {{{"name", "vlab"}, {"nodes", roots}}}},
               {"nodes", nodes},
               {"meshes", meshes_json},
               {"animations", {{{"name", "run"}, {"samplers", samplers}, {"channels", channels}}}},
               {"accessors", buffer.accessors()},
               {"bufferViews", buffer.views()}};
  textures.AddTo(&gltf);
  gltf.update(gltf_extra);
  std::string& bin = buffer.bin();
  while (bin.size() % 4) bin.push_back(0);
  gltf["buffers"] = {{{"byteLength", bin.size()}}};
  std::string text = gltf.dump();
  while (text.size() % 4) text.push_back(' ');

  // GLB: header, JSON chunk, BIN chunk (glTF 2.0, "Binary glTF Layout")
  std::string glb;
  PutU32(&glb, 0x46546C67);  // "glTF"
  PutU32(&glb, 2);
  PutU32(&glb, static_cast<std::uint32_t>(12 + 8 + text.size() + 8 + bin.size()));
  PutU32(&glb, static_cast<std::uint32_t>(text.size()));
  PutU32(&glb, 0x4E4F534A);  // "JSON"
  glb += text;
  PutU32(&glb, static_cast<std::uint32_t>(bin.size()));
  PutU32(&glb, 0x004E4942);  // "BIN"
  glb += bin;
  const std::string partial = glb_path + ".partial";
  {
    std::ofstream out(partial, std::ios::binary);
    out << glb;
    if (!out) throw InputError("vlab export: cannot write '" + partial + "'");
  }
  fs::rename(partial, glb_path);
  GltfSummary s;
  s.bodies = static_cast<int>(bodies);
  s.geoms = geoms;
  s.textures = textures.count();
  s.cameras = placed.cameras;
  s.lights = placed.lights;
  s.left_out = placed.skipped;
  s.frames = frames;
  s.duration_s = static_cast<double>(times.back()) - times.front();
  s.bytes = static_cast<long>(glb.size());
  return s;
}

}  // namespace vlab::view
