#include "view/view_model.h"

#include <cstring>

#include <nlohmann/json.hpp>

#include "core/core_errors.h"
#include "core/core_mujoco.h"
#include "render/image_codec.h"
#include "scene/scene_geometry.h"
#include "scene/scene_pose_frame.h"

namespace vlab::view {

namespace {

void PutBytes(std::string* out, const void* data, std::size_t n) { out->append(static_cast<const char*>(data), n); }

}  // namespace

std::string EncodeFrame(double time, double seq, const double* poses, int values) {
  std::string out;
  scene::EncodePoseFrame(time, seq, poses, values, &out);
  return out;
}

std::unique_ptr<ViewModel> ViewModel::Load(const std::string& path) {
  // the shared loader: a regular UTF-8 file of bounded size, includes checked, before MuJoCo opens it
  mjModel* m = nullptr;
  try {
    m = LoadModel(path).release();
  } catch (const InputError& e) {
    throw InputError(std::string("vlab view: ") + e.what());
  }
  std::unique_ptr<ViewModel> v(new ViewModel());
  v->m_ = m;
  v->d_ = mj_makeData(m);
  mj_kinematics(m, v->d_);
  return v;
}

ViewModel::~ViewModel() {
  if (d_) mj_deleteData(d_);
  if (m_) mj_deleteModel(m_);
}

bool ViewModel::MeshBytes(int id, std::string* out) const {
  if (id < 0 || id >= m_->nmesh) return false;
  const std::uint32_t nv = static_cast<std::uint32_t>(m_->mesh_vertnum[id]);
  const std::uint32_t nf = static_cast<std::uint32_t>(m_->mesh_facenum[id]);
  out->clear();
  PutBytes(out, &nv, 4);
  PutBytes(out, &nf, 4);
  PutBytes(out, m_->mesh_vert + 3 * m_->mesh_vertadr[id], 12 * nv);
  for (std::uint32_t i = 0; i < 3 * nf; ++i) {
    const std::uint32_t index = static_cast<std::uint32_t>(m_->mesh_face[3 * m_->mesh_faceadr[id] + i]);
    PutBytes(out, &index, 4);
  }
  return true;
}

bool ViewModel::TexturePng(int id, std::string* out) const {
  if (id < 0 || id >= m_->ntex) return false;
  const int w = m_->tex_width[id], h = m_->tex_height[id];
  // MuJoCo keeps RGB rows top-down
  std::vector<std::uint8_t> png;
  try {
    render::EncodePng({w, h, 3, 8, m_->tex_rgb + m_->tex_adr[id], 0}, -1, &png);
  } catch (const render::ImageCodecError&) {
    return false;
  }
  out->assign(png.begin(), png.end());
  return true;
}

nlohmann::json ViewModel::Cameras() const {
  nlohmann::json cameras = nlohmann::json::array();
  for (int c = 0; c < m_->ncam; ++c) {
    if (m_->cam_bodyid[c] != 0) continue;
    const char* name = mj_id2name(m_, mjOBJ_CAMERA, c);
    cameras.push_back(
        {{"name", name ? name : ""},
         {"pos", {m_->cam_pos[3 * c], m_->cam_pos[3 * c + 1], m_->cam_pos[3 * c + 2]}},
         {"quat", {m_->cam_quat[4 * c], m_->cam_quat[4 * c + 1], m_->cam_quat[4 * c + 2], m_->cam_quat[4 * c + 3]}},
         {"fovy", m_->cam_fovy[c]}});
  }
  return cameras;
}

nlohmann::json ViewModel::Lights() const {
  nlohmann::json lights = nlohmann::json::array();
  for (int l = 0; l < m_->nlight; ++l) {
    if (m_->light_bodyid[l] != 0 || !m_->light_active[l]) continue;
    const char* name = mj_id2name(m_, mjOBJ_LIGHT, l);
    const mjtNum* pos = m_->light_pos + 3 * l;
    const mjtNum* dir = m_->light_dir + 3 * l;
    const float* diffuse = m_->light_diffuse + 3 * l;
    lights.push_back({{"name", name ? name : ""},
                      {"pos", {pos[0], pos[1], pos[2]}},
                      {"dir", {dir[0], dir[1], dir[2]}},
                      {"directional", m_->light_directional[l] != 0},
                      {"castshadow", m_->light_castshadow[l] != 0},
                      {"diffuse", {diffuse[0], diffuse[1], diffuse[2]}},
                      {"cutoff", m_->light_cutoff[l]}});
  }
  return lights;
}

void ViewModel::BindJoints(const std::vector<std::string>& names) {
  qpos_adr_.clear();
  for (const std::string& name : names) {
    const int j = mj_name2id(m_, mjOBJ_JOINT, name.c_str());
    if (j < 0) throw InputError("vlab view: the model has no joint '" + name + "' (named by the arm's describe reply)");
    if (m_->jnt_type[j] != mjJNT_HINGE && m_->jnt_type[j] != mjJNT_SLIDE) {
      throw InputError("vlab view: joint '" + name + "' is not a hinge or slide joint");
    }
    qpos_adr_.push_back(m_->jnt_qposadr[j]);
  }
}

void ViewModel::ArmPoses(const std::vector<double>& q, const std::vector<int>& bodies, double* out) {
  for (std::size_t i = 0; i < qpos_adr_.size() && i < q.size(); ++i) d_->qpos[qpos_adr_[i]] = q[i];
  mj_kinematics(m_, d_);
  scene::ScenePoses(*d_, bodies, out);
}

}  // namespace vlab::view
