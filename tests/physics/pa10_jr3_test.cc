// The JR3 at rest under the PA10's tool, in the real scene (scenes/pa10.xml), against statics.
//
// The arm is held exactly still at a configuration: qpos set, qvel = 0, and the motors S1..W2
// (unit-gear torque motors) given ctrl = qfrc_bias, the gravity torque (with qvel = 0 the bias
// force is gravity only), so mj_forward solves the ordinary forward dynamics with qacc = 0.
// We use the forward pipeline rather than mj_inverse because it is the one the lab runs
// (mj_forward -> mj_sensorAcc -> cfrc_int): the MJCF force/torque sensors are read exactly as
// in a simulation step; qacc = 0 and no active constraint are asserted, so it is the static case.
//
// At rest the measuring plane carries the weight of everything beyond it, the subtree
// {jr3_tool_side, tool_body}. The load that subtree applies to the sensor, in the sensor frame S:
//   F = m_beyond R_WS' g_W,   M = c_S x F    (c_S: the subtree's COM in S, about the site origin)
// computed here from the raw model arrays (body_pos, body_quat, jnt_axis, body_ipos, body_mass,
// site_pos, site_quat) with our own kinematics; MuJoCo's kinematics are only cross-checked.
// The load goes through the JR3 model (sensors/sensor_wrench.h) with filter 4.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <Eigen/Geometry>

#include "mujoco_fixture.h"
#include "sensors/sensor_wrench.h"

namespace vlab::sensors {
namespace {

constexpr int kDof = 7;
constexpr double kStep = 0.001;         // physics step, s
constexpr int kStepsPerRun = 1000;      // 1 s
constexpr double kJr3HalfMass = 0.085;  // kg, mjcf/pa10/README.md "JR3 67M25A sensor"
constexpr double kToolMass = 0.3416;    // kg, README: adapter 0.1428 + pointer 0.1988

Eigen::Vector3d Vec(const mjtNum* v) { return Eigen::Vector3d(v[0], v[1], v[2]); }
Eigen::Matrix3d Rot(const mjtNum* q) {
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
}
Eigen::Matrix3d RotFromXmat(const mjtNum* xmat) {
  Eigen::Matrix3d r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r(i, j) = xmat[3 * i + j];
  }
  return r;
}

// what the test computes from the model arrays for one configuration
struct AnalyticLoad {
  Wrench load;            // [F; M] in the sensor frame, the load of the subtree on the sensor
  Eigen::Matrix3d R_WS;   // sensor frame in world, own composition
  Eigen::Vector3d com_S;  // subtree COM in the sensor frame
  double mass = 0;
};

class Pa10Jr3 : public vlab::test::MujocoTest {
 protected:
  void SetUp() override {
    model_ = LoadModel("scenes/pa10.xml");
    data_ = MakeData(model_);
    const mjModel* m = model_;
    ASSERT_EQ(m->nq, kDof);
    ASSERT_EQ(m->nu, kDof);
    site_ = mj_name2id(m, mjOBJ_SITE, "jr3");
    tool_side_ = mj_name2id(m, mjOBJ_BODY, "jr3_tool_side");
    tool_ = mj_name2id(m, mjOBJ_BODY, "tool_body");
    const int force = mj_name2id(m, mjOBJ_SENSOR, "jr3_force");
    const int torque = mj_name2id(m, mjOBJ_SENSOR, "jr3_torque");
    ASSERT_GE(site_, 0);
    ASSERT_GE(tool_side_, 0);
    ASSERT_GE(tool_, 0);
    ASSERT_GE(force, 0);
    ASSERT_GE(torque, 0);
    ASSERT_EQ(m->sensor_type[force], mjSENS_FORCE);
    ASSERT_EQ(m->sensor_type[torque], mjSENS_TORQUE);
    ASSERT_EQ(m->sensor_objid[force], site_);
    ASSERT_EQ(m->sensor_objid[torque], site_);
    force_adr_ = m->sensor_adr[force];
    torque_adr_ = m->sensor_adr[torque];

    // actuators: one unit-gear motor per joint, in qpos order, so ctrl = joint torque
    for (int i = 0; i < kDof; ++i) {
      ASSERT_EQ(m->actuator_trntype[i], mjTRN_JOINT);
      ASSERT_EQ(m->jnt_dofadr[m->actuator_trnid[2 * i]], i);
      ASSERT_EQ(m->actuator_gear[6 * i], 1.0);
      ASSERT_EQ(m->jnt_type[i], mjJNT_HINGE);
    }
    ASSERT_EQ(Vec(m->opt.gravity), Eigen::Vector3d(0, 0, -9.81)) << "scenes/pa10.xml gravity";
  }

  // Holds the arm at q (see the file comment) and returns the JR3 load from MuJoCo's sensors.
  // Fails (and returns false) if the pose is not a clean static case.
  bool HoldStatic(const Eigen::VectorXd& q, Wrench& mujoco_load) {
    const mjModel* m = model_;
    mjData* d = data_;
    mj_resetData(m, d);
    for (int i = 0; i < kDof; ++i) d->qpos[i] = q[i];
    mj_forward(m, d);
    for (int i = 0; i < kDof; ++i) d->ctrl[i] = d->qfrc_bias[i];
    mj_forward(m, d);
    double max_qacc = 0;
    for (int i = 0; i < kDof; ++i) max_qacc = std::max(max_qacc, std::abs(d->qacc[i]));
    if (d->ncon != 0 || d->nefc != 0 || max_qacc > 1e-9) {
      ADD_FAILURE() << "not static: ncon " << d->ncon << ", nefc " << d->nefc << ", max |qacc| " << max_qacc;
      return false;
    }
    mujoco_load = LoadFromMujocoSensor(d->sensordata + force_adr_, d->sensordata + torque_adr_);
    return true;
  }

  // Own kinematics: R_WS from the chain world -> site composed from body_quat and the hinge
  // rotations about their body-local axes (body_pos and jnt_pos do not affect orientation),
  // and the subtree COM from body_pos/body_quat/body_ipos in the jr3_tool_side frame.
  AnalyticLoad Analytic(const Eigen::VectorXd& q) const {
    const mjModel* m = model_;
    AnalyticLoad out;
    std::vector<int> chain;
    for (int b = m->site_bodyid[site_]; b > 0; b = m->body_parentid[b]) chain.push_back(b);
    std::reverse(chain.begin(), chain.end());
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    for (int b : chain) {
      R = R * Rot(m->body_quat + 4 * b);
      for (int j = m->body_jntadr[b]; j >= 0 && j < m->body_jntadr[b] + m->body_jntnum[b]; ++j) {
        R = R * Eigen::AngleAxisd(q[m->jnt_qposadr[j]], Vec(m->jnt_axis + 3 * j).normalized()).toRotationMatrix();
      }
    }
    out.R_WS = R * Rot(m->site_quat + 4 * site_);

    // COMs in the jr3_tool_side frame B; tool_body is a rigid child of B (asserted in the test)
    const double m1 = m->body_mass[tool_side_], m2 = m->body_mass[tool_];
    const Eigen::Vector3d com1_B = Vec(m->body_ipos + 3 * tool_side_);
    const Eigen::Vector3d com2_B =
        Vec(m->body_pos + 3 * tool_) + Rot(m->body_quat + 4 * tool_) * Vec(m->body_ipos + 3 * tool_);
    const Eigen::Vector3d com_B = (m1 * com1_B + m2 * com2_B) / (m1 + m2);
    out.com_S = Rot(m->site_quat + 4 * site_).transpose() * (com_B - Vec(m->site_pos + 3 * site_));
    out.mass = m1 + m2;

    const Eigen::Vector3d f_S = out.mass * (out.R_WS.transpose() * Vec(m->opt.gravity));
    out.load << f_S, out.com_S.cross(f_S);
    return out;
  }

  // configurations: the two keyframes and seeded random ones within the joint limits that
  // have no contact (4.7 % of random poses touch, mjcf/pa10/README.md)
  std::vector<Eigen::VectorXd> Configurations(int random_count) {
    const mjModel* m = model_;
    std::vector<Eigen::VectorXd> out;
    for (const char* key : {"zero", "ready"}) {
      const int k = mj_name2id(m, mjOBJ_KEY, key);
      EXPECT_GE(k, 0) << key;
      if (k >= 0) out.push_back(Eigen::Map<const Eigen::VectorXd>(m->key_qpos + k * m->nq, kDof));
    }
    std::mt19937 rng(20240611);
    while (static_cast<int>(out.size()) < 2 + random_count) {
      Eigen::VectorXd q(kDof);
      for (int i = 0; i < kDof; ++i) {
        // 2 % inside each limit so that no limit constraint is near
        const double lo = m->jnt_range[2 * i], hi = m->jnt_range[2 * i + 1], pad = 0.02 * (hi - lo);
        q[i] = std::uniform_real_distribution<double>(lo + pad, hi - pad)(rng);
      }
      mj_resetData(m, data_);
      for (int i = 0; i < kDof; ++i) data_->qpos[i] = q[i];
      mj_forward(m, data_);
      if (data_->ncon == 0) out.push_back(q);
    }
    return out;
  }

  // 1 s of 1 ms physics steps at the held pose, each step re-running mj_forward and feeding the
  // sensor reading to the JR3; returns the max |reading - expected| per axis over the readings
  // from `from_step` on, and the last reading
  Wrench RunSensor(const WrenchSensorModel& jr3, const Eigen::VectorXd& q, const Wrench& expected, int from_step,
                   Wrench& last_reading) {
    WrenchSensorState state;
    Reset(jr3, state);  // switched on (and tared) unloaded; the filters settle within the run
    Wrench worst = Wrench::Zero();
    for (int step = 0; step < kStepsPerRun; ++step) {
      Wrench load;
      if (!HoldStatic(q, load)) return Wrench::Constant(INFINITY);
      const WrenchReading reading = Update(jr3, state, load, kStep);
      EXPECT_EQ(reading.status, WrenchStatus::kOk);
      EXPECT_EQ(reading.samples, 8u);
      EXPECT_FALSE(reading.saturated);
      if (step >= from_step) worst = worst.cwiseMax((reading.wrench - expected).cwiseAbs());
      last_reading = reading.wrench;
    }
    return worst;
  }

  const mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
  int site_ = -1, tool_side_ = -1, tool_ = -1, force_adr_ = 0, torque_adr_ = 0;
};

TEST_F(Pa10Jr3, SubtreeBeyondTheMeasuringPlaneIsTheToolSideHalfAndTheTool) {
  const mjModel* m = model_;
  EXPECT_EQ(m->site_bodyid[site_], tool_side_);
  EXPECT_EQ(m->body_parentid[tool_], tool_side_);
  EXPECT_EQ(m->body_parentid[tool_side_], mj_name2id(m, mjOBJ_BODY, "jr3_body"));
  // README "JR3 67M25A sensor": the JR3 is a child of link 7 at the flange face
  const int jr3_body = mj_name2id(m, mjOBJ_BODY, "jr3_body");
  ASSERT_GE(jr3_body, 0);
  EXPECT_EQ(m->body_parentid[jr3_body], mj_name2id(m, mjOBJ_BODY, "pa10_link7"))
      << "the JR3 is mounted on " << mj_id2name(m, mjOBJ_BODY, m->body_parentid[jr3_body]);
  std::vector<int> subtree;
  for (int b = 1; b < m->nbody; ++b) {
    for (int a = b; a > 0; a = m->body_parentid[a]) {
      if (a == tool_side_) {
        subtree.push_back(b);
        break;
      }
    }
  }
  EXPECT_EQ(subtree, (std::vector<int>{tool_side_, tool_}));
  EXPECT_EQ(m->body_jntnum[tool_side_], 0);
  EXPECT_EQ(m->body_jntnum[tool_], 0);
  EXPECT_NEAR(m->body_mass[tool_side_], kJr3HalfMass, 1e-9);
  EXPECT_NEAR(m->body_mass[tool_], kToolMass, 1e-9);
  // the measuring plane: 12.5 mm above the flange face, axes = flange axes
  const int flange = mj_name2id(m, mjOBJ_SITE, "flange");
  ASSERT_GE(flange, 0);
  for (const Eigen::VectorXd& q : Configurations(3)) {
    for (int i = 0; i < kDof; ++i) data_->qpos[i] = q[i];
    mj_forward(m, data_);
    const Eigen::Matrix3d R_WF = RotFromXmat(data_->site_xmat + 9 * flange);
    const Eigen::Matrix3d R_WS = RotFromXmat(data_->site_xmat + 9 * site_);
    EXPECT_LT((R_WS - R_WF).norm(), 1e-12);
    EXPECT_LT(
        (Vec(data_->site_xpos + 3 * site_) - Vec(data_->site_xpos + 3 * flange) - R_WF * Eigen::Vector3d(0, 0, 0.0125))
            .norm(),
        1e-12);
  }
}

TEST_F(Pa10Jr3, OwnKinematicsAgreeWithMujoco) {
  const mjModel* m = model_;
  for (const Eigen::VectorXd& q : Configurations(6)) {
    const AnalyticLoad a = Analytic(q);
    Wrench unused;
    ASSERT_TRUE(HoldStatic(q, unused));
    const mjData* d = data_;
    const Eigen::Matrix3d R_WS = RotFromXmat(d->site_xmat + 9 * site_);
    EXPECT_LT((a.R_WS - R_WS).norm(), 1e-12) << q.transpose();
    const Eigen::Vector3d com_W =
        (m->body_mass[tool_side_] * Vec(d->xipos + 3 * tool_side_) + m->body_mass[tool_] * Vec(d->xipos + 3 * tool_)) /
        a.mass;
    const Eigen::Vector3d com_S = R_WS.transpose() * (com_W - Vec(d->site_xpos + 3 * site_));
    EXPECT_LT((a.com_S - com_S).norm(), 1e-12) << q.transpose();
  }
}

// Ideal sensor: the only differences left are round-off in MuJoCo's RNE (cfrc_int), the
// counts <-> N conversion and the filters (DC gain 1; after 1 s filter 4, the slowest stage
// in its path at 7.8 Hz, has settled to e^(-2 pi 7.8 * 0.707 * 1 s) = 1e-15 of the step):
// 1e-9 of full scale is many orders above that and ~1e6 below any frame or sign error.
TEST_F(Pa10Jr3, IdealSensorReadsTheStaticLoadExactly) {
  WrenchSensorConfig config;
  config.enable_noise = config.enable_bias = config.enable_quantization = false;
  config.filter = 4;
  const auto jr3 = WrenchSensorModel::Create(config);
  double worst_fraction = 0;
  for (const Eigen::VectorXd& q : Configurations(8)) {
    const AnalyticLoad a = Analytic(q);
    Wrench mujoco_load, last;
    ASSERT_TRUE(HoldStatic(q, mujoco_load));
    const Wrench raw_error = (mujoco_load - a.load).cwiseQuotient(jr3->full_scale());
    EXPECT_LT(raw_error.cwiseAbs().maxCoeff(), 1e-12) << "MuJoCo sensordata, q " << q.transpose();
    RunSensor(*jr3, q, a.load, 0, last);
    const Wrench fraction = (last - a.load).cwiseQuotient(jr3->full_scale()).cwiseAbs();
    worst_fraction = std::max(worst_fraction, fraction.maxCoeff());
    EXPECT_LT(fraction.maxCoeff(), 1e-9) << "q " << q.transpose() << "\nread     " << last.transpose() << "\nanalytic "
                                         << a.load.transpose();
    // the load is not trivially small: it would show any error
    EXPECT_NEAR(a.load.head<3>().norm(), a.mass * 9.81, 1e-12);
  }
  std::cout << "ideal JR3, filter 4 after 1 s: worst |reading - analytic| / full scale " << worst_fraction << "\n";
}

// Default sensor (noise, bias, quantisation on), filter 4, seed 1. Per axis i the reading
// differs from the true load by
//   bias      b_i ~ N(0, bias_sigma_i), drawn once at Reset: |b_i| < 5 bias_sigma_i;
//   noise     white noise_sigma_i per 8 kHz sample through the cascade to filter 4 (2-pole
//             Butterworth, cut-off fc4 = fs / 1024 = 7.8 Hz, noise-equivalent bandwidth
//             1.111 fc4; stages 1..3 are flat there): sigma4 = noise_sigma sqrt(2 * 1.111 fc4 / fs)
//             = 0.047 noise_sigma; |n| < 5 sigma4;
//   rounding  filter 0 is rounded to 1 lsb, but the noise (33 lsb) dithers it to a zero-mean
//             error that the filters average away; the reported filter-4 value is rounded to
//             the nearest count: at most 0.5 lsb, we allow 1 lsb.
// 5 sigma: two-sided tail 6e-7 per axis; with ~40 independent filter-4 samples per second the
// check over 0.5 s is still far from a chance failure, and it is deterministic (seed 1).
// The bound is 0.3 % of full scale (0.3 N, 0.015 N m): the tool's weight is 4.2 N, the
// jr3_body half (a wrong subtree) 0.83 N, and the 12.5 mm lever to the flange (a wrong
// reference point) up to 0.05 N m.
TEST_F(Pa10Jr3, DefaultSensorReadsTheStaticLoadWithinNoiseBiasAndQuantisation) {
  WrenchSensorConfig config;
  config.filter = 4;
  const auto jr3 = WrenchSensorModel::Create(config);
  ASSERT_TRUE(jr3->noise_enabled() && jr3->bias_enabled() && jr3->quantization_enabled());
  const double fs = jr3->sample_rate_hz();
  const double fc4 = jr3->stage(4).cutoff_hz;
  ASSERT_NEAR(fc4, fs / 1024, 1e-12);
  const Wrench sigma4 = jr3->noise_sigma() * std::sqrt(2 * 1.111 * fc4 / fs);
  const Wrench bound = 5 * jr3->bias_sigma() + 5 * sigma4 + jr3->lsb();
  std::cout << "bound per axis [N, N m]: " << bound.transpose() << "\n";
  for (int i = 0; i < 6; ++i) ASSERT_GT(bound[i], 0.0);

  Wrench worst_fraction_of_bound = Wrench::Zero();
  for (const Eigen::VectorXd& q : Configurations(8)) {
    const AnalyticLoad a = Analytic(q);
    Wrench last;
    // readings over the second half (the filters settle from the unloaded Reset in ~0.1 s)
    const Wrench worst = RunSensor(*jr3, q, a.load, kStepsPerRun / 2, last);
    worst_fraction_of_bound = worst_fraction_of_bound.cwiseMax(worst.cwiseQuotient(bound));
    for (int i = 0; i < 6; ++i) {
      EXPECT_LT(worst[i], bound[i]) << "axis " << i << ", q " << q.transpose() << "\nread     " << last.transpose()
                                    << "\nanalytic " << a.load.transpose();
    }
    // the reading is quantised to whole counts
    const Wrench counts = last.cwiseQuotient(jr3->lsb());
    for (int i = 0; i < 6; ++i) EXPECT_DOUBLE_EQ(counts[i], std::round(counts[i])) << "axis " << i;
  }
  std::cout << "default JR3, filter 4, last 0.5 s: worst |reading - analytic| / bound per axis "
            << worst_fraction_of_bound.transpose() << "\n";
}

}  // namespace
}  // namespace vlab::sensors
