#include "lab/devices/arm_servo_model.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <locale>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "core/core_errors.h"

namespace vlab::lab {

namespace {

// a body's name for messages
std::string BodyName(const mjModel& m, int body) {
  const char* name = mj_id2name(&m, mjOBJ_BODY, body);
  return name ? "'" + std::string(name) + "'" : "#" + std::to_string(body);
}

std::string JointName(const mjModel& m, int joint) {
  const char* name = mj_id2name(&m, mjOBJ_JOINT, joint);
  return name ? "'" + std::string(name) + "'" : "#" + std::to_string(joint);
}

// numbers written so that the compiled model reads back the same doubles
std::string Numbers(const double* v, int n) {
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out << std::setprecision(17);
  for (int i = 0; i < n; ++i) out << (i ? " " : "") << v[i];
  return out.str();
}

// the world's numbers for the servo model: which bodies, and how they hang together
struct Chain {
  const mjModel& m;
  std::vector<int> servo_parent;           // per world body: nearest ancestor kept, 0 for a root, -1 not kept
  std::vector<std::vector<int>> children;  // per world body: kept bodies whose servo parent it is
  std::vector<int> roots;
  int flange = -1;
};

// pose of `body`'s frame (at qpos0) in the frame of its ancestor `top`, folding the bodies between
void RelativePose(const mjModel& m, int top, int body, double pos[3], double quat[4]) {
  std::vector<int> path;
  for (int b = body; b != top; b = m.body_parentid[b]) path.push_back(b);
  mju_zero3(pos);
  quat[0] = 1;
  quat[1] = quat[2] = quat[3] = 0;
  for (auto it = path.rbegin(); it != path.rend(); ++it) {
    double step[3], q[4];
    mju_rotVecQuat(step, m.body_pos + 3 * *it, quat);
    mju_addTo3(pos, step);
    mju_mulQuat(q, quat, m.body_quat + 4 * *it);
    mju_copy4(quat, q);
  }
}

// one body of the servo model, with its inertial, its joints and its kept children
void WriteBody(const Chain& c, const std::vector<int>& arm_index, int body, std::ostringstream& out) {
  const mjModel& m = c.m;
  double pos[3] = {0, 0, 0}, quat[4] = {1, 0, 0, 0};  // a root is placed at run time
  if (c.servo_parent[body] > 0) RelativePose(m, c.servo_parent[body], body, pos, quat);
  out << "<body name=\"b" << body << "\" pos=\"" << Numbers(pos, 3) << "\" quat=\"" << Numbers(quat, 4) << "\">\n";
  if (m.body_mass[body] > 0) {
    out << "<inertial pos=\"" << Numbers(m.body_ipos + 3 * body, 3) << "\" quat=\""
        << Numbers(m.body_iquat + 4 * body, 4) << "\" mass=\"" << Numbers(m.body_mass + body, 1) << "\" diaginertia=\""
        << Numbers(m.body_inertia + 3 * body, 3) << "\"/>\n";
  }
  for (int j = m.body_jntadr[body]; j >= 0 && j < m.body_jntadr[body] + m.body_jntnum[body]; ++j) {
    out << "<joint name=\"j" << arm_index[j] << "\" type=\"" << (m.jnt_type[j] == mjJNT_HINGE ? "hinge" : "slide")
        << "\" pos=\"" << Numbers(m.jnt_pos + 3 * j, 3) << "\" axis=\"" << Numbers(m.jnt_axis + 3 * j, 3) << "\" ref=\""
        << Numbers(m.qpos0 + m.jnt_qposadr[j], 1) << "\" armature=\"" << Numbers(m.dof_armature + m.jnt_dofadr[j], 1)
        << "\"/>\n";
  }
  if (body == c.flange) {
    // the payload: a welded body in the flange frame, its numbers set by SetPayload
    out << "<body name=\"payload\"><inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"1 1 1\"/></body>\n";
  }
  for (int child : c.children[body]) WriteBody(c, arm_index, child, out);
  out << "</body>\n";
}

}  // namespace

bool CheckPayload(const Payload& p, std::string* field, std::string* reason) {
  // one rule for the scenario key, SetPayload and the wire (bridge_payload.h)
  const char* f = nullptr;
  const char* r = nullptr;
  if (bridge::CheckArmPayload(PayloadToWire(p), &f, &r)) return true;
  *field = f;
  *reason = r;
  return false;
}

bridge::ArmPayloadMsg PayloadToWire(const Payload& p) {
  bridge::ArmPayloadMsg m;
  m.mass_kg = p.mass_kg;
  for (int k = 0; k < 3; ++k) m.com_m[k] = p.com_m[k];
  m.inertia_kgm2 = p.inertia_kgm2;
  return m;
}

Payload PayloadFromWire(const bridge::ArmPayloadMsg& m) {
  Payload p;
  p.mass_kg = m.mass_kg;
  p.com_m = Eigen::Vector3d(m.com_m[0], m.com_m[1], m.com_m[2]);
  p.inertia_kgm2 = m.inertia_kgm2;
  return p;
}

std::unique_ptr<ArmServoModel> ArmServoModel::Create(const mjModel& m, const std::vector<int>& joints,
                                                     const std::vector<std::string>& bodies) {
  // the kept bodies: those carrying the arm's joints, and the named ones
  std::vector<bool> kept(m.nbody, false), moved(m.nbody, false);
  std::vector<int> arm_index(m.njnt, -1);
  for (std::size_t i = 0; i < joints.size(); ++i) {
    arm_index[joints[i]] = static_cast<int>(i);
    kept[m.jnt_bodyid[joints[i]]] = true;
  }
  for (int b = 1; b < m.nbody; ++b) moved[b] = kept[b] || moved[m.body_parentid[b]];  // parents come first
  for (const std::string& name : bodies) {
    const int b = mj_name2id(&m, mjOBJ_BODY, name.c_str());
    if (b < 0) throw InputError("servo.bodies: no body '" + name + "' in the scene");
    if (!moved[b]) throw InputError("servo.bodies: body '" + name + "' is not moved by the arm's joints");
    kept[b] = true;
  }

  // each kept body hangs from its nearest kept ancestor; nothing between may move by itself
  Chain chain{m, std::vector<int>(m.nbody, -1), std::vector<std::vector<int>>(m.nbody), {}, -1};
  chain.flange = m.jnt_bodyid[joints.back()];
  for (int b = 1; b < m.nbody; ++b) {
    if (!kept[b]) continue;
    for (int j = m.body_jntadr[b]; j >= 0 && j < m.body_jntadr[b] + m.body_jntnum[b]; ++j) {
      if (arm_index[j] < 0) {
        throw InputError("servo model: body " + BodyName(m, b) + " has joint " + JointName(m, j) +
                         ", which is not one of the arm's joints");
      }
    }
    int parent = m.body_parentid[b];
    while (parent > 0 && !kept[parent]) parent = m.body_parentid[parent];
    chain.servo_parent[b] = parent;
    if (parent == 0) {
      chain.roots.push_back(b);
      continue;
    }
    chain.children[parent].push_back(b);
    for (int between = m.body_parentid[b]; between != parent; between = m.body_parentid[between]) {
      if (m.body_jntnum[between] > 0) {
        throw InputError("servo model: body " + BodyName(m, between) + " between the arm's bodies " +
                         BodyName(m, parent) + " and " + BodyName(m, b) + " has joint " +
                         JointName(m, m.body_jntadr[between]) + ", which is not one of the arm's joints");
      }
    }
  }

  // the servo model's text: no geoms, the world's gravity, angles in radians
  double gravity[3];
  mju_copy3(gravity, m.opt.gravity);
  if (m.opt.disableflags & mjDSBL_GRAVITY) mju_zero3(gravity);
  std::ostringstream xml;
  xml << "<mujoco model=\"arm_servo\">\n<compiler angle=\"radian\" inertiafromgeom=\"false\"/>\n"
      << "<option gravity=\"" << Numbers(gravity, 3) << "\"/>\n<worldbody>\n";
  for (int root : chain.roots) WriteBody(chain, arm_index, root, xml);
  xml << "</worldbody>\n</mujoco>\n";

  std::unique_ptr<ArmServoModel> servo(new ArmServoModel());
  servo->xml_ = xml.str();
  try {
    servo->model_ = LoadModelFromString("arm_servo.xml", servo->xml_);
  } catch (const InputError& e) {
    throw InputError(std::string("servo model: ") + e.what());
  }
  const mjModel* s = servo->model_.get();
  servo->data_ = MakeData(s);
  servo->rne_.assign(s->nv, 0.0);
  servo->rne_pass_ = std::make_unique<ChainRne>(*s);
  servo->payload_body_ = mj_name2id(s, mjOBJ_BODY, "payload");
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const int j = mj_name2id(s, mjOBJ_JOINT, ("j" + std::to_string(i)).c_str());
    servo->world_qpos_adr_.push_back(m.jnt_qposadr[joints[i]]);
    servo->world_dof_adr_.push_back(m.jnt_dofadr[joints[i]]);
    servo->qpos_adr_.push_back(s->jnt_qposadr[j]);
    servo->dof_adr_.push_back(s->jnt_dofadr[j]);
  }
  for (int root : chain.roots) {
    servo->root_servo_body_.push_back(mj_name2id(s, mjOBJ_BODY, ("b" + std::to_string(root)).c_str()));
    servo->root_world_parent_.push_back(m.body_parentid[root]);
    servo->root_offset_pos_.insert(servo->root_offset_pos_.end(), m.body_pos + 3 * root, m.body_pos + 3 * root + 3);
    servo->root_offset_quat_.insert(servo->root_offset_quat_.end(), m.body_quat + 4 * root, m.body_quat + 4 * root + 4);
  }
  servo->SetPayload(Payload{});
  return servo;
}

void ArmServoModel::Place(const mjData& d) {
  for (std::size_t r = 0; r < root_servo_body_.size(); ++r) {
    // the root's frame before its joints: its world parent's frame, then its own offset
    const int body = root_servo_body_[r];
    const int parent = root_world_parent_[r];
    double offset[3];
    mju_rotVecQuat(offset, root_offset_pos_.data() + 3 * r, d.xquat + 4 * parent);
    mju_add3(model_->body_pos + 3 * body, d.xpos + 3 * parent, offset);
    mju_mulQuat(model_->body_quat + 4 * body, d.xquat + 4 * parent, root_offset_quat_.data() + 4 * r);
  }
  rne_pass_->Refresh(*model_);
}

bool ArmServoModel::SetPayload(const Payload& p, std::string* why) {
  std::string field, reason;
  if (!CheckPayload(p, &field, &reason)) {
    if (why) *why = field + ": " + reason;
    return false;
  }
  payload_ = p;
  mjModel* s = model_.get();
  const int b = payload_body_;
  // principal axes: the eigenvectors as a right-handed rotation of the flange frame
  const auto& i = p.inertia_kgm2;
  Eigen::Matrix3d inertia;
  inertia << i[0], i[3], i[4], i[3], i[1], i[5], i[4], i[5], i[2];
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(inertia);
  Eigen::Matrix3d axes = eigen.eigenvectors();
  if (axes.determinant() < 0) axes.col(2) *= -1.0;
  double rotation[9];
  for (int r = 0; r < 3; ++r) {
    for (int col = 0; col < 3; ++col) rotation[3 * r + col] = axes(r, col);
  }
  s->body_mass[b] = p.mass_kg;
  for (int k = 0; k < 3; ++k) {
    s->body_ipos[3 * b + k] = p.com_m[k];
    s->body_inertia[3 * b + k] = std::max(0.0, eigen.eigenvalues()[k]);
  }
  mju_mat2Quat(s->body_iquat + 4 * b, rotation);
  s->body_sameframe[b] = 0;  // the compiler saw the placeholder's frame: kinematics must apply ipos, iquat
  // subtree masses follow (the com pass divides by them)
  for (int k = 0; k < s->nbody; ++k) s->body_subtreemass[k] = s->body_mass[k];
  for (int k = s->nbody - 1; k > 0; --k) s->body_subtreemass[s->body_parentid[k]] += s->body_subtreemass[k];
  if (rne_pass_) rne_pass_->Refresh(*s);
  return true;
}

void ArmServoModel::CopyState(const mjData& world, bool with_velocity) {
  for (std::size_t i = 0; i < qpos_adr_.size(); ++i) {
    data_->qpos[qpos_adr_[i]] = world.qpos[world_qpos_adr_[i]];
    data_->qvel[dof_adr_[i]] = with_velocity ? world.qvel[world_dof_adr_[i]] : 0.0;
  }
}

void ArmServoModel::Bias(const mjData& world, double* tau) {
  CopyState(world, true);
  BiasOfState(tau);
}

void ArmServoModel::Bias(const double* q, const double* qd, double* tau) {
  for (std::size_t i = 0; i < qpos_adr_.size(); ++i) {
    data_->qpos[qpos_adr_[i]] = q[i];
    data_->qvel[dof_adr_[i]] = qd[i];
  }
  BiasOfState(tau);
}

void ArmServoModel::BiasOfState(double* tau) {
  rne_pass_->Bias(*model_, data_->qpos, data_->qvel, rne_.data());
  for (std::size_t i = 0; i < dof_adr_.size(); ++i) tau[i] = rne_[dof_adr_[i]];
}

void ArmServoModel::InertiaDiagonal(const mjData& world, double* h) {
  const mjModel* s = model_.get();
  CopyState(world, false);
  mj_kinematics(s, data_.get());
  mj_comPos(s, data_.get());
  mj_crb(s, data_.get());
  for (std::size_t i = 0; i < dof_adr_.size(); ++i) h[i] = data_->qM[s->dof_Madr[dof_adr_[i]]];
}

}  // namespace vlab::lab
