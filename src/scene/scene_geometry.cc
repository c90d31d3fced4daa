#include "scene/scene_geometry.h"

#include <string>

#include <nlohmann/json.hpp>

namespace vlab::scene {

namespace {

// a geom a viewer draws: MuJoCo's default visible groups, not fully transparent
bool Visible(const mjModel* m, int geom) {
  const int mat = m->geom_matid[geom];
  const float alpha = mat >= 0 ? m->mat_rgba[4 * mat + 3] : m->geom_rgba[4 * geom + 3];
  return m->geom_group[geom] >= 0 && m->geom_group[geom] <= 2 && alpha > 0;
}

const char* GeomTypeName(int type) {
  switch (type) {
    case mjGEOM_PLANE:
      return "plane";
    case mjGEOM_SPHERE:
      return "sphere";
    case mjGEOM_CAPSULE:
      return "capsule";
    case mjGEOM_ELLIPSOID:
      return "ellipsoid";
    case mjGEOM_CYLINDER:
      return "cylinder";
    case mjGEOM_BOX:
      return "box";
    case mjGEOM_MESH:
      return "mesh";
    default:
      return "other";
  }
}

std::string NameOf(const mjModel* m, mjtObj type, int id) {
  const char* name = mj_id2name(m, type, id);
  return name ? name : "";
}

template <class T>
nlohmann::json Array(const T* values, int n) {
  nlohmann::json a = nlohmann::json::array();
  for (int i = 0; i < n; ++i) a.push_back(values[i]);
  return a;
}

}  // namespace

std::vector<int> SceneBodies(const mjModel* m) {
  std::vector<char> has(m->nbody, 0);
  for (int g = 0; g < m->ngeom; ++g) {
    if (Visible(m, g)) has[m->geom_bodyid[g]] = 1;
  }
  std::vector<int> bodies;
  for (int b = 1; b < m->nbody; ++b) {
    if (has[b]) bodies.push_back(b);
  }
  return bodies;
}

nlohmann::json SceneGeometry(const mjModel* m, const std::vector<int>& bodies) {
  std::vector<int> index(m->nbody, -1);
  nlohmann::json names = nlohmann::json::array();
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    index[bodies[i]] = static_cast<int>(i);
    names.push_back(NameOf(m, mjOBJ_BODY, bodies[i]));
  }
  nlohmann::json geoms = nlohmann::json::array();
  for (int g = 0; g < m->ngeom; ++g) {
    if (!Visible(m, g)) continue;
    const int mat = m->geom_matid[g];
    nlohmann::json j;
    j["name"] = NameOf(m, mjOBJ_GEOM, g);
    j["body"] = index[m->geom_bodyid[g]];  // -1: the world (static)
    j["type"] = GeomTypeName(m->geom_type[g]);
    j["size"] = Array(m->geom_size + 3 * g, 3);
    j["pos"] = Array(m->geom_pos + 3 * g, 3);
    j["quat"] = Array(m->geom_quat + 4 * g, 4);
    j["rgba"] = mat >= 0 ? Array(m->mat_rgba + 4 * mat, 4) : Array(m->geom_rgba + 4 * g, 4);
    j["mesh"] = m->geom_type[g] == mjGEOM_MESH ? m->geom_dataid[g] : -1;
    const int tex = mat >= 0 ? m->mat_texid[mat] : -1;
    j["texture"] = tex;
    if (tex >= 0) {
      j["texrepeat"] = Array(m->mat_texrepeat + 2 * mat, 2);
      j["texuniform"] = m->mat_texuniform[mat] != 0;
    }
    geoms.push_back(j);
  }
  nlohmann::json meshes = nlohmann::json::array();
  for (int i = 0; i < m->nmesh; ++i) {
    meshes.push_back(
        {{"name", NameOf(m, mjOBJ_MESH, i)}, {"vertices", m->mesh_vertnum[i]}, {"faces", m->mesh_facenum[i]}});
  }
  nlohmann::json textures = nlohmann::json::array();
  for (int i = 0; i < m->ntex; ++i) {
    const char* type = m->tex_type[i] == mjTEXTURE_2D ? "2d" : m->tex_type[i] == mjTEXTURE_CUBE ? "cube" : "skybox";
    textures.push_back({{"name", NameOf(m, mjOBJ_TEXTURE, i)},
                        {"type", type},
                        {"width", m->tex_width[i]},
                        {"height", m->tex_height[i]}});
  }
  return {{"bodies", names}, {"geoms", geoms}, {"meshes", meshes}, {"textures", textures}};
}

void ScenePoses(const mjData& d, const std::vector<int>& bodies, double* out) {
  for (int b : bodies) {
    for (int i = 0; i < 3; ++i) *out++ = d.xpos[3 * b + i];
    for (int i = 0; i < 4; ++i) *out++ = d.xquat[4 * b + i];
  }
}

}  // namespace vlab::scene
