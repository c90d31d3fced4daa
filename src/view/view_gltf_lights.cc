// `vlab export`'s cameras and lights: the MJCF's cameras as glTF perspective
// cameras and its lights as KHR_lights_punctual lights, on the nodes of the
// bodies that carry them.
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "view/view_gltf_parts.h"

namespace vlab::view::gltf {

using nlohmann::json;

namespace {

// the pose of frame `local` (pos, quat in body b's frame) in the frame of body `parent`
// (-1: the world), both from the model's kinematics at qpos0 (they are welded together)
Attachment Relative(const mjData* d, int b, int parent, const mjtNum* pos, const mjtNum* quat) {
  mjtNum p_world[3], q_world[4];
  mju_rotVecQuat(p_world, pos, d->xquat + 4 * b);
  mju_addTo3(p_world, d->xpos + 3 * b);
  mju_mulQuat(q_world, d->xquat + 4 * b, quat);
  Attachment a;
  a.parent = parent;
  if (parent < 0) {
    mju_copy3(a.pos, p_world);
    mju_copy4(a.quat, q_world);
    return a;
  }
  mjtNum q_inverse[4], offset[3];
  mju_negQuat(q_inverse, d->xquat + 4 * parent);
  mju_sub3(offset, p_world, d->xpos + 3 * parent);
  mju_rotVecQuat(a.pos, offset, q_inverse);
  mju_mulQuat(a.quat, q_inverse, q_world);
  return a;
}

// where a camera or light of body b goes: the world's frame for the world and bodies welded
// to it, the node of b when it is recorded, else of a recorded body welded to b; none (parent
// -2) when b moves on its own and nothing welded to it is recorded
Attachment Attach(const mjModel* m, const mjData* d, const std::vector<int>& recorded, int b, const mjtNum* pos,
                  const mjtNum* quat) {
  const auto node = std::find(recorded.begin(), recorded.end(), b);
  if (node != recorded.end() || b == 0) {
    Attachment a;
    a.parent = b == 0 ? -1 : static_cast<int>(node - recorded.begin());
    mju_copy3(a.pos, pos);
    mju_copy4(a.quat, quat);
    return a;
  }
  const int weld = m->body_weldid[b];
  if (weld == 0) return Relative(d, b, -1, pos, quat);
  for (std::size_t i = 0; i < recorded.size(); ++i) {
    if (m->body_weldid[recorded[i]] == weld) return Relative(d, b, recorded[i], pos, quat);
  }
  Attachment none;
  none.parent = -2;
  return none;
}

// the rotation that turns -z (where a glTF light shines) into `dir`
void QuatFromMinusZ(const mjtNum* dir, mjtNum* quat) {
  mjtNum v[3] = {dir[0], dir[1], dir[2]};
  if (mju_normalize3(v) < mjMINVAL) v[2] = -1;
  const mjtNum dot = -v[2];  // (0, 0, -1) . v
  if (dot < -1 + 1e-12) {    // opposite: half a turn about x
    quat[0] = 0, quat[1] = 1, quat[2] = 0, quat[3] = 0;
    return;
  }
  // (1 + a.b, a x b), normalised, with a = (0, 0, -1)
  quat[0] = 1 + dot;
  quat[1] = v[1];
  quat[2] = -v[0];
  quat[3] = 0;
  mju_normalize4(quat);
}

json Node(const std::string& name, const Attachment& a) {
  return {{"name", name},
          {"translation", {a.pos[0], a.pos[1], a.pos[2]}},
          {"rotation", {a.quat[1], a.quat[2], a.quat[3], a.quat[0]}}};  // glTF: x, y, z, w
}

void Place(json node, const Attachment& a, json* nodes, json* roots) {
  nodes->push_back(std::move(node));
  const std::size_t index = nodes->size() - 1;
  if (a.parent < 0) {
    roots->push_back(index);
  } else {
    json& parent = (*nodes)[a.parent];
    if (!parent.contains("children")) parent["children"] = json::array();
    parent["children"].push_back(index);
  }
}

std::string NameOf(const mjModel* m, mjtObj type, int id, const char* kind) {
  const char* name = mj_id2name(m, type, id);
  return name && *name ? name : std::string(kind) + " " + std::to_string(id);
}

}  // namespace

CameraLightCounts AddCamerasAndLights(const mjModel* m, const std::vector<int>& recorded, json* nodes, json* roots,
                                      json* gltf) {
  CameraLightCounts counts;
  if (!m) return counts;
  std::unique_ptr<mjData, void (*)(mjData*)> d(mj_makeData(m), mj_deleteData);
  mj_kinematics(m, d.get());
  const double extent = m->stat.extent;
  json cameras = json::array(), lights = json::array();
  for (int c = 0; c < m->ncam; ++c) {
    const Attachment a = Attach(m, d.get(), recorded, m->cam_bodyid[c], m->cam_pos + 3 * c, m->cam_quat + 4 * c);
    if (a.parent == -2) {
      ++counts.skipped;
      continue;
    }
    // a MuJoCo camera looks along its -z with +y up, as a glTF camera does: the same frame
    const std::string name = NameOf(m, mjOBJ_CAMERA, c, "camera");
    cameras.push_back({{"name", name},
                       {"type", "perspective"},
                       {"perspective",
                        {{"yfov", m->cam_fovy[c] * M_PI / 180},
                         {"znear", m->vis.map.znear * extent},
                         {"zfar", m->vis.map.zfar * extent}}}});
    json node = Node(name, a);
    node["camera"] = cameras.size() - 1;
    Place(node, a, nodes, roots);
    ++counts.cameras;
  }
  for (int l = 0; l < m->nlight; ++l) {
    if (!m->light_active[l]) continue;
    mjtNum quat[4];
    QuatFromMinusZ(m->light_dir + 3 * l, quat);
    const Attachment a = Attach(m, d.get(), recorded, m->light_bodyid[l], m->light_pos + 3 * l, quat);
    if (a.parent == -2) {
      ++counts.skipped;
      continue;
    }
    const std::string name = NameOf(m, mjOBJ_LIGHT, l, "light");
    const float* diffuse = m->light_diffuse + 3 * l;
    const double top = std::max({diffuse[0], diffuse[1], diffuse[2]});
    json light = {{"name", name}, {"intensity", top}};
    light["color"] = top > 0 ? json{diffuse[0] / top, diffuse[1] / top, diffuse[2] / top} : json{1.0, 1.0, 1.0};
    const double cutoff_rad = m->light_cutoff[l] * M_PI / 180;
    if (m->light_directional[l]) {
      light["type"] = "directional";
    } else if (cutoff_rad > 0 && cutoff_rad < M_PI / 2) {
      light["type"] = "spot";
      light["spot"] = {{"innerConeAngle", 0.0}, {"outerConeAngle", cutoff_rad}};
    } else {
      light["type"] = "point";
    }
    lights.push_back(light);
    json node = Node(name, a);
    node["extensions"] = {{"KHR_lights_punctual", {{"light", lights.size() - 1}}}};
    Place(node, a, nodes, roots);
    ++counts.lights;
  }
  if (!cameras.empty()) (*gltf)["cameras"] = cameras;
  if (!lights.empty()) {
    (*gltf)["extensions"] = {{"KHR_lights_punctual", {{"lights", lights}}}};
    (*gltf)["extensionsUsed"] = {"KHR_lights_punctual"};
  }
  return counts;
}

}  // namespace vlab::view::gltf
