#include "identify/identify_problem.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <limits>
#include <thread>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/QR>

#include "core/core_clock.h"
#include "core/core_errors.h"
#include "lab/devices/device_arm.h"
#include "lab/devices/device_counter.h"
#include "lab/devices/device_wrench.h"
#include "lab/run/lab_runner.h"
#include "lab/scenario/lab_scenario.h"
#include "scene/scene_csv.h"

namespace vlab::identify {

namespace {

std::string JoinNames(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size() && i < 20; ++i) out += (i ? ", " : "") + names[i];
  if (names.size() > 20) out += ", ...";
  return out;
}

// each column of `m` about row `row` as a + b x + c x² (x in rows from it): a quadratic
// least-squares fit over the rows within `half` of it (fewer at a log's ends); with half 0 the
// row itself and the parabola through it and the next two rows
Eigen::MatrixXd QuadraticAbout(const Eigen::MatrixXd& m, int row, int half) {
  const int rows = static_cast<int>(m.rows());
  Eigen::MatrixXd out(m.cols(), 3);
  if (half == 0 || rows < 4) {
    const int r1 = std::min(row + 1, rows - 1), r2 = std::min(row + 2, rows - 1);
    for (Eigen::Index j = 0; j < m.cols(); ++j) {
      const double y0 = m(row, j), y1 = m(r1, j), y2 = m(r2, j);
      const bool three = r2 == row + 2;
      out.row(j) << y0, three ? (-3 * y0 + 4 * y1 - y2) / 2 : y1 - y0, three ? (y0 - 2 * y1 + y2) / 2 : 0.0;
    }
    return out;
  }
  const int lo = std::max(0, row - half), hi = std::min(rows - 1, row + half);
  Eigen::MatrixXd a(hi - lo + 1, 3);
  for (int i = lo; i <= hi; ++i) {
    const double x = i - row;
    a.row(i - lo) << 1.0, x, x * x;
  }
  return a.colPivHouseholderQr().solve(m.middleRows(lo, hi - lo + 1)).transpose();
}

// the time after which the selected filter's response to a unit step stays within 1e-3 of
// it, the filter fed every `dt` as the lab feeds it; in rows of `period`
int SettleRows(const sensors::WrenchSensorModel& model, double dt, double period) {
  sensors::WrenchSensorState state;
  sensors::Reset(model, state, sensors::Wrench::Zero());
  const sensors::Wrench step = 0.5 * model.full_scale();  // within the ADC's range
  double last = 0;
  const int steps = static_cast<int>(std::ceil(20.0 / dt));  // 20 s: 60 time constants of filter 6
  for (int i = 1; i <= steps; ++i) {
    sensors::WrenchReading flags;
    sensors::Advance(model, state, step, dt, &flags);
    const sensors::Wrench y = sensors::ReadSelected(model, state);
    if ((y.cwiseQuotient(step).array() - 1.0).abs().maxCoeff() > 1e-3) last = i * dt;
  }
  return static_cast<int>(std::ceil(last / period - 1e-9));
}

// start_speed: the counter's readings within this many gates of a window's start are fitted
constexpr double kStartSpeedGates = 10;

// a derived column's value from its parts now and a row before (spec `norm:`, `rate:`): the log's
// and the replay's alike
double DerivedValue(const Eigen::Ref<const Eigen::VectorXd>& now, const Eigen::Ref<const Eigen::VectorXd>& before,
                    bool rate, double period) {
  return rate ? (now - before).norm() / period : now.norm();
}

}  // namespace

bool Problem::Column::settles() const {
  if (wrench >= 0) return true;
  for (const Column& p : parts) {
    if (p.wrench >= 0) return true;
  }
  return false;
}

bool Problem::Column::Counts(double time_s) const {
  if (spans.empty()) return true;
  for (const auto& [from, to] : spans) {
    if (time_s >= from - kSameTime_s && time_s <= to + kSameTime_s) return true;
  }
  return false;
}

void AddPointMass(double payload_mass, const double payload_com[3], double* mass, double ipos[3], double inertia[3],
                  double iquat[4]) {
  if (payload_mass == 0) return;
  const double m1 = *mass, total = m1 + payload_mass;
  const Eigen::Map<const Eigen::Vector3d> c2(payload_com);
  const Eigen::Vector3d c1(ipos[0], ipos[1], ipos[2]);
  const Eigen::Vector3d c = (m1 * c1 + payload_mass * c2) / total;
  const Eigen::Matrix3d r = Eigen::Quaterniond(iquat[0], iquat[1], iquat[2], iquat[3]).normalized().toRotationMatrix();
  // both inertias about the combined centre of mass, in the body's frame (parallel axes)
  auto shift = [](double m, const Eigen::Vector3d& d) {
    return Eigen::Matrix3d(m * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose()));
  };
  const Eigen::Matrix3d sum = r * Eigen::Vector3d(inertia[0], inertia[1], inertia[2]).asDiagonal() * r.transpose() +
                              shift(m1, c1 - c) + shift(payload_mass, c2 - c);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(sum);
  Eigen::Matrix3d axes = eig.eigenvectors();
  if (axes.determinant() < 0) axes.col(0) = -axes.col(0);  // a rotation, not a reflection
  const Eigen::Quaterniond q(axes);
  *mass = total;
  for (int k = 0; k < 3; ++k) {
    ipos[k] = c[k];
    inertia[k] = std::max(0.0, eig.eigenvalues()[k]);
  }
  iquat[0] = q.w();
  iquat[1] = q.x();
  iquat[2] = q.y();
  iquat[3] = q.z();
}

std::unique_ptr<Problem> Problem::Create(const Spec& spec, int threads) {
  std::unique_ptr<Problem> p(new Problem());
  p->spec_ = spec;
  p->reference_ = spec.input == "reference";
  const lab::Scenario scenario = lab::LoadScenario(spec.scenario, spec.sets);
  p->seed_ = scenario.seed;
  std::unique_ptr<lab::Lab> lab = lab::Lab::Create(scenario);
  p->scene_ = scenario.scene;
  p->model_.reset(mj_copyModel(nullptr, lab->model()));
  DataPtr data = MakeData(p->model_.get());
  lab->InitialState(data.get());
  p->qpos_init_.assign(data->qpos, data->qpos + p->model_->nq);
  p->qvel_init_.assign(data->qvel, data->qvel + p->model_->nv);
  p->BindJoints(scenario);
  p->BindWrenches(scenario);
  p->BindCounters(scenario);
  p->BindColumns();
  p->BindParameters();
  p->CheckInertias();
  p->arm_dof_.assign(p->model_->nv, false);
  for (const Joint& j : p->joints_) p->arm_dof_[j.dof] = true;
  p->run_in_steps_ = static_cast<int>(std::lround(spec.run_in_s / p->model_->opt.timestep));
  p->ReadLogs();
  p->CutWindows();
  if (spec.skip_contacts) p->SkipContactWindows(threads);
  if (p->start_counter_ >= 0) p->StartSpeedGains(threads);
  return p;
}

void Problem::BindJoints(const lab::Scenario& scenario) {
  const mjModel* m = model_.get();
  for (const lab::DeviceConfig& device : scenario.devices) {
    if (device.kind != bridge::DeviceKind::kArm) continue;
    const lab::ArmParams& arm = device.ParamsAs<lab::ArmParams>();
    arms_.push_back({device, static_cast<int>(joints_.size()), static_cast<int>(arm.joints.size()), -1, -1});
    for (std::size_t i = 0; i < arm.joints.size(); ++i) {
      Joint j;
      j.device = device.name;
      j.name = arm.joints[i];
      const int id = mj_name2id(m, mjOBJ_JOINT, j.name.c_str());
      const std::string actuator = i < arm.actuators.size() ? arm.actuators[i] : j.name;
      j.actuator = mj_name2id(m, mjOBJ_ACTUATOR, actuator.c_str());
      // the lab has bound these names already: a miss is a bug, not bad input
      if (id < 0 || j.actuator < 0)
        throw std::logic_error("arm '" + device.name + "': joint or motor not in the model");
      j.qpos = m->jnt_qposadr[id];
      j.dof = m->jnt_dofadr[id];
      joints_.push_back(j);
    }
  }
  if (joints_.empty()) {
    throw InputError(spec_.file + ": scenario '" + spec_.scenario +
                     "' has no arm device: the torque replay needs one (its q, qd and tau columns)");
  }
}

void Problem::BindWrenches(const lab::Scenario& scenario) {
  const mjModel* m = model_.get();
  for (const lab::DeviceConfig& device : scenario.devices) {
    if (device.kind != bridge::DeviceKind::kWrench) continue;
    const lab::WrenchParams& params = device.ParamsAs<lab::WrenchParams>();
    WrenchSensor w;
    w.device = device.name;
    const int force = mj_name2id(m, mjOBJ_SENSOR, params.force_sensor.c_str());
    const int torque = mj_name2id(m, mjOBJ_SENSOR, params.torque_sensor.c_str());
    // the lab has bound these names already: a miss is a bug, not bad input
    if (force < 0 || torque < 0) throw std::logic_error("wrench '" + device.name + "': sensor not in the model");
    w.force_adr = m->sensor_adr[force];
    w.torque_adr = m->sensor_adr[torque];
    // the device's own JR3 model, what it adds to the reading taken out: the bias is a
    // parameter of the fit, the noise and rounding are the measurement's
    sensors::WrenchSensorConfig config = lab::WrenchSensorConfigOf(params, 1);
    config.enable_noise = config.enable_bias = config.enable_quantization = false;
    w.model = sensors::WrenchSensorModel::Create(config);
    wrenches_.push_back(std::move(w));
  }
}

void Problem::BindCounters(const lab::Scenario& scenario) {
  const mjModel* m = model_.get();
  const double period = scenario.control_period_s;
  for (const lab::DeviceConfig& device : scenario.devices) {
    if (device.kind != bridge::DeviceKind::kCounter) continue;
    const lab::CounterParams& params = device.ParamsAs<lab::CounterParams>();
    const int id = mj_name2id(m, mjOBJ_JOINT, params.joint.c_str());
    // the lab has bound this name already: a miss is a bug, not bad input
    if (id < 0) throw std::logic_error("counter '" + device.name + "': joint not in the model");
    counters_.push_back(
        {device.name, m->jnt_qposadr[id], m->jnt_dofadr[id], params.rate_hz > 0 ? 1.0 / params.rate_hz : period});
  }
  if (spec_.start_speed.empty()) return;
  std::vector<std::string> names;
  for (std::size_t i = 0; i < counters_.size(); ++i) {
    names.push_back(counters_[i].device + ".rpm");
    if (names.back() == spec_.start_speed) start_counter_ = static_cast<int>(i);
  }
  if (start_counter_ < 0) {
    throw InputError(spec_.where_start_speed + ": '" + spec_.start_speed +
                     "' is no counter device's speed column (the scenario's: " +
                     (names.empty() ? std::string("none") : JoinNames(names)) + ")");
  }
  start_speed0_ = qvel_init_[counters_[start_counter_].dof] * lab::kRpmPerRadPerSecond;
  if (!(std::abs(start_speed0_) > 1e-9)) {
    throw InputError(spec_.where_start_speed + ": the counter's joint is at rest in the scenario's initial state: " +
                     "there is no motion to scale (give the scenario a keyframe in which it turns)");
  }
}

void Problem::BindColumns() {
  // the columns a rollout predicts: every arm joint's q and qd, and with input: reference the
  // torque its servo applies; every wrench device's axes
  std::vector<std::string> predictable;
  std::vector<Column> kinds;
  auto joint_column = [](int joint, bool velocity, bool torque) {
    Column c;
    c.joint = joint;
    c.velocity = velocity;
    c.torque = torque;
    return c;
  };
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    predictable.push_back(joints_[j].device + ".q." + joints_[j].name);
    kinds.push_back(joint_column(static_cast<int>(j), false, false));
    predictable.push_back(joints_[j].device + ".qd." + joints_[j].name);
    kinds.push_back(joint_column(static_cast<int>(j), true, false));
    if (!reference_) continue;
    predictable.push_back(joints_[j].device + ".tau." + joints_[j].name);
    kinds.push_back(joint_column(static_cast<int>(j), false, true));
  }
  for (std::size_t w = 0; w < wrenches_.size(); ++w) {
    int axis = 0;
    for (const char* name : lab::kWrenchAxes) {
      predictable.push_back(wrenches_[w].device + "." + name);
      Column c;
      c.joint = -1;
      c.wrench = static_cast<int>(w);
      c.axis = axis++;
      kinds.push_back(c);
    }
  }
  for (std::size_t i = 0; i < counters_.size(); ++i) {
    predictable.push_back(counters_[i].device + ".rpm");
    Column c;
    c.joint = -1;
    c.counter = static_cast<int>(i);
    kinds.push_back(c);
  }
  for (const ColumnSpec& c : spec_.columns) {
    if (!c.norm.empty()) {
      // a derived column: its parts are columns the replay predicts, named in full
      Column derived;
      derived.joint = -1;
      derived.rate = c.rate;
      derived.part = part_count_;
      for (const std::string& name : c.norm) {
        const auto it = std::find(predictable.begin(), predictable.end(), name);
        if (it == predictable.end() || kinds[it - predictable.begin()].counter >= 0) {
          throw InputError(c.where + ".norm: '" + name +
                           "' is none of the columns a norm can take (an arm's q, qd or torque, a wrench "
                           "device's axis): " +
                           JoinNames(predictable));
        }
        derived.parts.push_back(kinds[it - predictable.begin()]);
        derived.part_names.push_back(name);
      }
      part_count_ += static_cast<int>(derived.parts.size());
      if (std::find(column_names_.begin(), column_names_.end(), c.pattern) != column_names_.end() ||
          std::find(predictable.begin(), predictable.end(), c.pattern) != predictable.end()) {
        throw InputError(c.where + ".name: '" + c.pattern + "' is taken: name the derived column apart");
      }
      column_names_.push_back(c.pattern);
      weights_.push_back(c.weight);
      derived.spans = c.spans;
      if (derived.settles()) ++wrench_columns_;
      columns_.push_back(std::move(derived));
      continue;
    }
    bool any = false;
    for (std::size_t i = 0; i < predictable.size(); ++i) {
      if (!MatchColumn(c.pattern, predictable[i])) continue;
      any = true;
      if (std::find(column_names_.begin(), column_names_.end(), predictable[i]) != column_names_.end()) {
        throw InputError(c.where + ".name: '" + c.pattern + "' names column " + predictable[i] +
                         " that an earlier entry names already");
      }
      column_names_.push_back(predictable[i]);
      weights_.push_back(c.weight);
      columns_.push_back(kinds[i]);
      columns_.back().spans = c.spans;
      if (kinds[i].wrench >= 0) ++wrench_columns_;
    }
    if (!any) {
      throw InputError(c.where + ".name: '" + c.pattern +
                       "' names none of the columns the replay predicts: " + JoinNames(predictable));
    }
  }
}

void Problem::BindParameters() {
  const mjModel* m = model_.get();
  for (const ParameterSpec& spec : spec_.parameters) {
    BoundParameter p;
    p.spec = spec;
    const std::string where = spec.where + ".target";
    double model_value = 0;
    switch (spec.kind) {
      case TargetKind::kBodyMass:
      case TargetKind::kBodyCom:
      case TargetKind::kBodyInertia:
      case TargetKind::kPayloadMass:
      case TargetKind::kPayloadCom: {
        p.index = mj_name2id(m, mjOBJ_BODY, spec.element.c_str());
        if (p.index <= 0)
          throw InputError(where + ": no body '" + spec.element + "' in the scene (the world's is not one)");
        p.mass0 = m->body_mass[p.index];
        if (spec.kind == TargetKind::kBodyMass && !(p.mass0 > 0))
          throw InputError(where + ": body '" + spec.element + "' has no mass to scale its inertia with");
        for (int i = 0; i < 3; ++i) p.inertia0[i] = m->body_inertia[3 * p.index + i];
        auto edit = std::find_if(bodies_.begin(), bodies_.end(), [&](const BodyEdit& e) { return e.body == p.index; });
        if (edit == bodies_.end()) {
          BodyEdit e;
          e.body = p.index;
          e.mass0 = p.mass0;
          for (int i = 0; i < 3; ++i) {
            e.ipos0[i] = m->body_ipos[3 * p.index + i];
            e.inertia0[i] = p.inertia0[i];
          }
          for (int i = 0; i < 4; ++i) e.iquat0[i] = m->body_iquat[4 * p.index + i];
          bodies_.push_back(e);
          edit = bodies_.end() - 1;
        }
        const int self = static_cast<int>(parameters_.size());
        switch (spec.kind) {
          case TargetKind::kBodyMass:
            edit->mass = self;
            model_value = p.mass0;
            break;
          case TargetKind::kBodyCom:
            edit->com[spec.axis] = self;
            model_value = edit->ipos0[spec.axis];
            break;
          case TargetKind::kBodyInertia:
            edit->inertia[spec.axis] = self;
            model_value = edit->inertia0[spec.axis];
            break;
          case TargetKind::kPayloadMass:
            edit->payload_mass = self;
            model_value = 0;  // the model has none
            break;
          default:
            edit->payload_com[spec.axis] = self;
            model_value = 0;
            break;
        }
        break;
      }
      case TargetKind::kJointDamping:
      case TargetKind::kJointArmature:
      case TargetKind::kJointFrictionLoss: {
        const int id = mj_name2id(m, mjOBJ_JOINT, spec.element.c_str());
        if (id < 0) throw InputError(where + ": no joint '" + spec.element + "' in the scene");
        if (m->jnt_type[id] != mjJNT_HINGE && m->jnt_type[id] != mjJNT_SLIDE) {
          throw InputError(where + ": joint '" + spec.element + "' is not a hinge or slide joint");
        }
        p.index = m->jnt_dofadr[id];
        model_value = spec.kind == TargetKind::kJointDamping    ? m->dof_damping[p.index]
                      : spec.kind == TargetKind::kJointArmature ? m->dof_armature[p.index]
                                                                : m->dof_frictionloss[p.index];
        break;
      }
      case TargetKind::kColumnBias:
      case TargetKind::kColumnGain:
      case TargetKind::kColumnDelay: {
        std::vector<std::string> known;
        for (const Joint& j : joints_) {
          for (const char* quantity : {".q.", ".qd."}) known.push_back(j.device + quantity + j.name);
        }
        for (const WrenchSensor& w : wrenches_) {
          for (const char* axis : lab::kWrenchAxes) known.push_back(w.device + "." + axis);
        }
        if (std::find(known.begin(), known.end(), spec.element) == known.end()) {
          throw InputError(where + ": '" + spec.element +
                           "' is not a column the replay predicts (an arm's q or qd, a wrench device's axis: " +
                           JoinNames(known) + ")");
        }
        const auto it = std::find(column_names_.begin(), column_names_.end(), spec.element);
        if (it == column_names_.end()) {
          throw InputError(where + ": column '" + spec.element + "' is not among the fitted columns");
        }
        p.index = static_cast<int>(it - column_names_.begin());
        if (spec.kind == TargetKind::kColumnDelay && columns_[p.index].wrench >= 0) {
          throw InputError(where + ": a delay is for an arm's q or qd column, not the wrench column '" + spec.element +
                           "' (its filter's lag is in the model already)");
        }
        int& slot = spec.kind == TargetKind::kColumnBias   ? columns_[p.index].bias
                    : spec.kind == TargetKind::kColumnGain ? columns_[p.index].gain
                                                           : columns_[p.index].delay;
        slot = static_cast<int>(parameters_.size());
        model_value = spec.kind == TargetKind::kColumnGain ? 1.0 : 0.0;
        break;
      }
      case TargetKind::kServoBandwidth:
      case TargetKind::kServoDampingRatio: {
        // (LoadSpec refused a servo target without input: reference)
        std::vector<std::string> names;
        for (const Arm& arm : arms_) names.push_back(arm.config.name);
        const auto it = std::find(names.begin(), names.end(), spec.element);
        if (it == names.end()) {
          throw InputError(where + ": no arm device '" + spec.element +
                           "' in the scenario (its arms: " + JoinNames(names) + ")");
        }
        Arm& arm = arms_[it - names.begin()];
        const lab::ServoConfig& servo = arm.config.ParamsAs<lab::ArmParams>().servo;
        p.index = static_cast<int>(it - names.begin());
        const bool bandwidth = spec.kind == TargetKind::kServoBandwidth;
        (bandwidth ? arm.bandwidth : arm.damping) = static_cast<int>(parameters_.size());
        model_value = bandwidth ? servo.bandwidth_hz : servo.damping_ratio;
        break;
      }
    }
    p.nominal = spec.has_nominal ? spec.nominal : model_value;
    if (p.nominal < spec.lower || p.nominal > spec.upper) {
      throw InputError(spec.where + ": the model's value " + std::to_string(model_value) + " of '" +
                       TargetText(spec.kind, spec.element, spec.axis) +
                       "' lies outside [lower, upper]: give a nominal");
    }
    p.scale = std::abs(p.nominal) > 0 ? std::abs(p.nominal) : std::max(std::abs(spec.lower), std::abs(spec.upper));
    parameters_.push_back(p);
  }
}

void Problem::CheckInertias() const {
  // a body's principal moments obey the triangle inequality (I_a + I_b >= I_c) at every value
  // the bounds allow, and a mass (which scales them) is fitted, or they are, not both
  for (const BodyEdit& e : bodies_) {
    int any = -1;
    for (int k = 0; k < 3; ++k) any = e.inertia[k] >= 0 ? e.inertia[k] : any;
    if (any < 0) continue;
    const ParameterSpec& spec = parameters_[any].spec;
    if (e.mass >= 0) {
      throw InputError(spec.where + ".target: body '" + spec.element +
                       "' has a mass parameter too, which scales its inertia: fit the one or the other");
    }
    double lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
      lo[k] = e.inertia[k] >= 0 ? parameters_[e.inertia[k]].spec.lower : e.inertia0[k];
      hi[k] = e.inertia[k] >= 0 ? parameters_[e.inertia[k]].spec.upper : e.inertia0[k];
    }
    for (int c = 0; c < 3; ++c) {
      const int a = (c + 1) % 3, b = (c + 2) % 3;
      if (lo[a] + lo[b] < hi[c] * (1 - 1e-12)) {
        throw InputError(
            spec.where + ": the bounds let body '" + spec.element + "''s principal moments break I_" +
            std::string(1, static_cast<char>('x' + a)) + " + I_" + std::string(1, static_cast<char>('x' + b)) +
            " >= I_" + std::string(1, static_cast<char>('x' + c)) + " (" + std::to_string(lo[a]) + " + " +
            std::to_string(lo[b]) + " < " + std::to_string(hi[c]) + " kg m^2), which no body has: narrow them");
      }
    }
  }
}

void Problem::ReadLogs() {
  const double timestep = model_->opt.timestep;
  for (const std::string& file : spec_.logs) {
    const scene::CsvTable table = scene::ReadCsvTable(file);
    Log log;
    const int time = table.Column("time");
    if (time < 0) throw InputError("log '" + file + "': no 'time' column");
    auto column = [&](const std::string& name) {
      const int c = table.Column(name);
      if (c < 0)
        throw InputError("log '" + file + "': no column '" + name +
                         "' (the replay needs every arm joint's q, qd, tau)");
      return c;
    };
    const int rows = static_cast<int>(table.rows.size());
    const int n = static_cast<int>(joints_.size());
    log.q.resize(rows, n);
    log.qd.resize(rows, n);
    log.tau.resize(rows, n);
    log.measured.resize(rows, static_cast<int>(columns_.size()));
    std::vector<int> q(n), qd(n), tau(n), fitted(columns_.size());
    for (int j = 0; j < n; ++j) {
      q[j] = column(joints_[j].device + ".q." + joints_[j].name);
      qd[j] = column(joints_[j].device + ".qd." + joints_[j].name);
      tau[j] = column(joints_[j].device + ".tau." + joints_[j].name);
    }
    // a derived column's parts, read into `parts` and combined once the period is known
    std::vector<int> part_column;
    for (std::size_t c = 0; c < columns_.size(); ++c) {
      fitted[c] = columns_[c].parts.empty() ? column(column_names_[c]) : -1;
      for (const std::string& name : columns_[c].part_names) part_column.push_back(column(name));
    }
    Eigen::MatrixXd parts(rows, part_column.size());
    const int start_speed = spec_.start_speed.empty() ? -1 : column(spec_.start_speed);
    for (int r = 0; r < rows; ++r) {
      const std::vector<double>& row = table.rows[r];
      log.time.push_back(row[time]);
      for (int j = 0; j < n; ++j) {
        log.q(r, j) = row[q[j]];
        log.qd(r, j) = row[qd[j]];
        log.tau(r, j) = row[tau[j]];
      }
      for (std::size_t c = 0; c < columns_.size(); ++c) {
        if (fitted[c] >= 0) log.measured(r, static_cast<int>(c)) = row[fitted[c]];
      }
      for (std::size_t i = 0; i < part_column.size(); ++i) parts(r, static_cast<Eigen::Index>(i)) = row[part_column[i]];
      if (start_speed >= 0) log.start_speed.push_back(row[start_speed]);
    }
    if (rows < 2) throw InputError("log '" + file + "': fewer than two rows");
    // rows one period apart, a whole number of physics steps
    const double period = log.time[1] - log.time[0];
    const double steps = std::round(period / timestep);
    if (!(steps >= 1) || std::abs(steps * timestep - period) > 1e-9 * std::max(1.0, period)) {
      throw InputError("log '" + file + "': rows " + std::to_string(period) +
                       " s apart, not a whole number of the scene's timesteps (" + std::to_string(timestep) + " s)");
    }
    for (int r = 1; r < rows; ++r) {
      if (std::abs(log.time[r] - log.time[r - 1] - period) > 1e-6 * period) {
        throw InputError("log '" + file + "': row " + std::to_string(r + 2) + " (time " + std::to_string(log.time[r]) +
                         "): rows are not evenly spaced (a gap, or a recording that lost states)");
      }
    }
    if (!logs_.empty() && static_cast<int>(steps) != steps_per_row_) {
      throw InputError("log '" + file + "': a period of " + std::to_string(period) + " s, unlike the first log's");
    }
    steps_per_row_ = static_cast<int>(steps);
    for (std::size_t c = 0; c < columns_.size(); ++c) {
      const Column& col = columns_[c];
      if (col.parts.empty()) continue;
      const int n_parts = static_cast<int>(col.parts.size());
      for (int r = 0; r < rows; ++r) {
        auto value = [&](int row) -> Eigen::VectorXd { return parts.row(row).segment(col.part, n_parts).transpose(); };
        // (row 0 has no rate: no window's row is row 0)
        log.measured(r, static_cast<int>(c)) =
            col.rate && r == 0 ? 0.0 : DerivedValue(value(r), value(std::max(r - 1, 0)), col.rate, period);
      }
    }
    ReadCounterGates(&log);
    if (reference_) ReadCommands(table, file, steps_per_row_, &log);
    logs_.push_back(std::move(log));
  }
}

void Problem::ReadCounterGates(Log* log) const {
  // the device's schedule: started at time 0, a reading at the first row at or after each
  // whole gate, over the gate since the last one
  const int rows = static_cast<int>(log->time.size());
  for (const CounterSensor& c : counters_) {
    std::vector<int> reading(rows, -1), gate(rows, -1);
    int last = -1, from = -1;
    double next = c.gate_s;
    for (int r = 0; r < rows; ++r) {
      if (r > 0 && lab::CounterReadingDue(log->time[r], c.gate_s, &next)) {
        from = last < 0 ? (log->time[0] <= kSameTime_s ? 0 : -1) : last;
        last = r;
      }
      reading[r] = last;
      gate[r] = last < 0 ? -1 : from;
    }
    log->reading.push_back(std::move(reading));
    log->gate.push_back(std::move(gate));
  }
}

double Problem::StartSpeed(const Log& log, int row, double from, double to) const {
  // the counter's readings whose gates lie within [from, to], each its mean speed at the
  // middle of its gate, nearest the row: a quadratic in time through them, at the row's time
  const std::vector<int>& reading = log.reading[start_counter_];
  const std::vector<int>& gate = log.gate[start_counter_];
  const double t0 = log.time[row];
  const double gate_s = counters_[start_counter_].gate_s;
  const double reach = kStartSpeedGates * gate_s + kSameTime_s;
  std::vector<double> t, v;
  for (std::size_t r = 1; r < reading.size(); ++r) {
    if (reading[r] != static_cast<int>(r) || gate[r] < 0) continue;  // no new reading here
    const double start = log.time[gate[r]], end = log.time[r];
    if (start < from - kSameTime_s || end > to + kSameTime_s) continue;
    const double mid = 0.5 * (start + end);
    if (std::abs(mid - t0) > reach) continue;
    t.push_back(mid - t0);
    v.push_back(log.start_speed[r]);
  }
  if (t.size() < 3) {
    throw InputError(spec_.where_start_speed + ": the window at " + std::to_string(t0) + " s of a log has " +
                     std::to_string(t.size()) + " reading(s) of '" + spec_.start_speed + "' within its span and " +
                     std::to_string(reach) +
                     " s of its start, fewer than the 3 a start speed is fitted from (start_smoothing, spans)");
  }
  Eigen::MatrixXd a(t.size(), 3);
  Eigen::VectorXd b(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    a.row(static_cast<Eigen::Index>(i)) << 1.0, t[i], t[i] * t[i];
    b[static_cast<Eigen::Index>(i)] = v[i];
  }
  return a.colPivHouseholderQr().solve(b)[0];
}

void Problem::CutWindows() {
  const double period = steps_per_row_ * model_->opt.timestep;
  const int rows = static_cast<int>(std::lround(spec_.window_s / period));
  if (rows < 1) {
    throw InputError(spec_.where_window + ": " + std::to_string(spec_.window_s) + " s is shorter than a log period (" +
                     std::to_string(period) + " s)");
  }
  if (wrench_columns_ > 0) {
    const double settle = spec_.wrench_settle_s;
    if (settle >= 0) {
      wrench_settle_rows_ = static_cast<int>(std::ceil(settle / period - 1e-9));
    } else {
      for (const WrenchSensor& w : wrenches_) {
        wrench_settle_rows_ = std::max(wrench_settle_rows_, SettleRows(*w.model, model_->opt.timestep, period));
      }
    }
    if (wrench_settle_rows_ >= rows) {
      throw InputError(spec_.where_window + ": windows of " + std::to_string(rows) + " rows leave no wrench row: " +
                       std::to_string(wrench_settle_rows_) + " rows (" + std::to_string(wrench_settle_rows_ * period) +
                       " s) at each window's start are its filter's settling (wrench_settle); make the windows longer");
    }
  }
  const int columns = static_cast<int>(columns_.size());
  for (std::size_t l = 0; l < logs_.size(); ++l) {
    const Log& log = logs_[l];
    const int n = static_cast<int>(log.time.size());
    std::vector<std::pair<double, double>> spans = spec_.spans;
    if (spans.empty()) spans.emplace_back(log.time.front(), log.time.back());
    for (const auto& [from, to] : spans) {
      // the span's rows: from its first row at or after `from` to its last at or before `to`
      int first = 0, end = n - 1;
      while (first < n && log.time[first] < from - kSameTime_s) ++first;
      while (end >= 0 && log.time[end] > to + kSameTime_s) --end;
      if (end <= first) continue;
      const int span_first = first;
      for (; first + rows <= end; first += rows) {
        Window w;
        w.log = static_cast<int>(l);
        w.first = first;
        w.rows = rows;
        w.offset = residual_count_;
        w.q0 = QuadraticAbout(log.q, first, spec_.start_smoothing);
        w.qd0 = QuadraticAbout(log.qd, first, spec_.start_smoothing);
        if (start_counter_ >= 0)
          w.speed_ratio = StartSpeed(log, first, log.time[span_first], log.time[end]) / start_speed0_;
        for (const Column& c : columns_) {
          for (int k = 1; k <= rows; ++k) w.left_out += !Counted(w, c, k);
        }
        windows_.push_back(w);
        residual_count_ += rows * columns;
      }
      rows_left_out_ += end - first;
    }
  }
  if (windows_.empty()) {
    throw InputError(spec_.where_window + ": " + std::to_string(spec_.window_s) + " s is longer than every log" +
                     (spec_.spans.empty() ? "" : "'s spans"));
  }
}

bool Problem::Counted(const Window& win, const Column& c, int k) const {
  const Log& log = logs_[win.log];
  const int row = win.first + k;
  // a wrench's filter state at the window's start is not known; nor are a counter's turns
  // before it, over a gate that began there
  const bool settling = c.settles() && k <= wrench_settle_rows_;
  const bool unseen = c.counter >= 0 && log.gate[c.counter][row] < win.first;
  return !settling && !unseen && c.Counts(log.time[row]);
}

std::vector<double> Problem::NominalValues() const {
  std::vector<double> nominal;
  for (const BoundParameter& p : parameters_) nominal.push_back(p.nominal);
  return nominal;
}

int Problem::residuals_left_out() const {
  int n = 0;
  for (const Window& w : windows_) n += w.left_out;
  return n;
}

void Problem::ForEachWindow(int threads, const std::function<void(int, Workspace&)>& fn) const {
  const int n = window_count();
  std::vector<std::exception_ptr> errors(n);
  std::atomic<int> next{0};
  auto work = [&]() {
    Workspace ws = MakeWorkspace();
    for (int w = next++; w < n; w = next++) {
      try {
        fn(w, ws);
      } catch (...) {
        errors[w] = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (int i = 1; i < std::min(std::max(1, threads), n); ++i) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

void Problem::SkipContactWindows(int threads) {
  const std::vector<double> nominal = NominalValues();
  std::vector<Window> kept;
  residual_count_ = 0;
  // a contact the recording went through shows in its recorded states, one the nominal model
  // would make in its replay
  auto recorded_contact = [&](const Window& win, Workspace& ws) {
    mjData* d = ws.data.get();
    for (int row = win.first; row <= win.first + win.rows; ++row) {
      std::copy(qpos_init_.begin(), qpos_init_.end(), d->qpos);
      for (std::size_t j = 0; j < joints_.size(); ++j) {
        d->qpos[joints_[j].qpos] = logs_[win.log].q(row, static_cast<int>(j));
      }
      mj_fwdPosition(ws.model.get(), d);
      if (d->ncon > 0) return true;
    }
    return false;
  };
  std::vector<char> in_contact(window_count());
  ForEachWindow(threads, [&](int w, Workspace& ws) {
    std::vector<double> r(window_residuals(w));
    const bool ok = Rollout(w, nominal, ws, r.data(), nullptr);
    in_contact[w] = !ok || ws.contacts > 0 || recorded_contact(windows_[w], ws);
  });
  for (int w = 0; w < window_count(); ++w) {
    if (in_contact[w]) {
      ++windows_in_contact_;
      continue;
    }
    kept.push_back(windows_[w]);
    kept.back().offset = residual_count_;
    residual_count_ += window_residuals(w);
  }
  windows_ = std::move(kept);
  if (windows_.empty()) {
    throw InputError(spec_.file +
                     ": every window's replay with the nominal model makes contact (or diverges): "
                     "nothing to fit (contacts: keep fits them anyway)");
  }
}

int Problem::window_residuals(int w) const { return windows_[w].rows * static_cast<int>(columns_.size()); }
int Problem::window_offset(int w) const { return windows_[w].offset; }

Workspace Problem::MakeWorkspace() const {
  Workspace ws;
  ws.model.reset(mj_copyModel(nullptr, model_.get()));
  ws.data = MakeData(ws.model.get());
  if (!reference_) return ws;
  // the arm devices' own servos on this model: commands come a log period apart
  const lab::DeviceContext context{ws.model.get(), steps_per_row_ * model_->opt.timestep, seed_, scene_};
  for (const Arm& arm : arms_) {
    lab::DeviceConfig config = arm.config;
    if (spec_.servo_sensing_exact) config.EditParams<lab::ArmParams>().sensing = {};  // (a copy: on write)
    ws.arms.push_back(lab::SimArm::Create(context, config));
  }
  return ws;
}

void Problem::Apply(const std::vector<double>& values, Workspace& ws) const {
  if (ws.applied == values) return;
  mjModel* m = ws.model.get();
  SetModel(values, m);
  // subtree masses and the constraint solver's inverse weights follow the masses and armature
  mj_setConst(m, ws.data.get());
  // the servo gains follow the joints' inertia at the initial pose, and the gain parameters
  if (reference_) TuneServos(values, ws);
  ws.applied = values;
}

void Problem::SetModel(const std::vector<double>& values, mjModel* m) const {
  for (const BodyEdit& e : bodies_) {
    // the body's own: a mass scales the inertia with it (the density changes; the centre of
    // mass stays), a moved centre of mass keeps the inertia about it
    double mass = e.mass0, ipos[3], inertia[3], iquat[4];
    for (int k = 0; k < 3; ++k) {
      ipos[k] = e.com[k] >= 0 ? values[e.com[k]] : e.ipos0[k];
      inertia[k] = e.inertia[k] >= 0 ? values[e.inertia[k]] : e.inertia0[k];
    }
    for (int k = 0; k < 4; ++k) iquat[k] = e.iquat0[k];
    if (e.mass >= 0 && values[e.mass] != e.mass0) {  // (the model's mass: its inertia to the bit)
      mass = values[e.mass];
      for (int k = 0; k < 3; ++k) inertia[k] = e.inertia0[k] * mass / e.mass0;
    }
    if (e.payload_mass >= 0) {
      const double at[3] = {e.payload_com[0] >= 0 ? values[e.payload_com[0]] : 0.0,
                            e.payload_com[1] >= 0 ? values[e.payload_com[1]] : 0.0,
                            e.payload_com[2] >= 0 ? values[e.payload_com[2]] : 0.0};
      AddPointMass(values[e.payload_mass], at, &mass, ipos, inertia, iquat);
    }
    m->body_mass[e.body] = mass;
    for (int k = 0; k < 3; ++k) {
      m->body_ipos[3 * e.body + k] = ipos[k];
      m->body_inertia[3 * e.body + k] = inertia[k];
    }
    for (int k = 0; k < 4; ++k) m->body_iquat[4 * e.body + k] = iquat[k];
  }
  for (std::size_t i = 0; i < parameters_.size(); ++i) {
    const BoundParameter& p = parameters_[i];
    const double v = values[i];
    switch (p.spec.kind) {
      case TargetKind::kBodyMass:
      case TargetKind::kBodyCom:
      case TargetKind::kBodyInertia:
      case TargetKind::kPayloadMass:
      case TargetKind::kPayloadCom:
        break;  // above, body by body
      case TargetKind::kJointDamping:
        m->dof_damping[p.index] = v;
        break;
      case TargetKind::kJointArmature:
        m->dof_armature[p.index] = v;
        break;
      case TargetKind::kJointFrictionLoss:
        m->dof_frictionloss[p.index] = v;
        break;
      case TargetKind::kColumnBias:
      case TargetKind::kColumnGain:
      case TargetKind::kColumnDelay:
        break;  // applied to the columns in Rollout
      case TargetKind::kServoBandwidth:
      case TargetKind::kServoDampingRatio:
        break;  // the servos' (TuneServos)
    }
  }
}

double Problem::TrueState(const Eigen::MatrixXd& fit, int joint, bool velocity,
                          const std::vector<double>& values) const {
  // a sensor delayed by d reads now what was true d ago: the true value now is the measured
  // one d later, x = d / period rows ahead on the measured fit
  double x = 0;
  const Column* column = nullptr;
  for (const Column& c : columns_) {
    if (c.joint == joint && c.velocity == velocity && !c.torque) column = &c;
  }
  if (column && column->delay >= 0) x = values[column->delay] / (steps_per_row_ * model_->opt.timestep);
  double v = fit(joint, 0) + fit(joint, 1) * x + fit(joint, 2) * x * x;
  if (column && column->bias >= 0) v -= values[column->bias];
  if (column && column->gain >= 0) v /= values[column->gain];
  return v;
}

bool Problem::Rollout(int w, const std::vector<double>& values, Workspace& ws, double* r, double* predicted) const {
  if (!Replay(w, values, windows_[w].speed_ratio, ws, r, predicted)) return false;
  const Window& win = windows_[w];
  if (win.speed_gain.empty()) return true;
  // the window's start speed profiled out: its residuals at the start speed that fits them
  // best, to first order along the gain (the start speed's error, the counter's rounding and
  // the rotor's ripple about the readings' trend, is no parameter the rest should absorb)
  const Eigen::Map<const Eigen::VectorXd> g(win.speed_gain.data(), static_cast<Eigen::Index>(win.speed_gain.size()));
  Eigen::Map<Eigen::VectorXd> res(r, g.size());
  const double delta = -g.dot(res) / g.squaredNorm();
  res += delta * g;
  if (predicted) {
    const int columns = static_cast<int>(columns_.size());
    for (Eigen::Index i = 0; i < g.size(); ++i) {
      if (g[i] != 0) predicted[i] += delta * g[i] / weights_[i % columns];
    }
  }
  return true;
}

void Problem::StartSpeedGains(int threads) {
  // each window's residuals per rpm of start speed, at the nominal values: the difference of
  // two replays 1e-3 of the start speed apart
  const std::vector<double> nominal = NominalValues();
  constexpr double kRelative = 1e-3;
  ForEachWindow(threads, [&](int w, Workspace& ws) {
    Window& win = windows_[w];
    std::vector<double> lo(window_residuals(w)), hi(window_residuals(w));
    const double step = win.speed_ratio * kRelative;
    if (!Replay(w, nominal, win.speed_ratio - step, ws, lo.data(), nullptr) ||
        !Replay(w, nominal, win.speed_ratio + step, ws, hi.data(), nullptr)) {
      throw InputError(spec_.file + ": the window at " + std::to_string(logs_[win.log].time[win.first]) +
                       " s of log '" + spec_.logs[win.log] + "' diverges in its nominal replay");
    }
    win.speed_gain.resize(lo.size());
    for (std::size_t i = 0; i < lo.size(); ++i) win.speed_gain[i] = (hi[i] - lo[i]) / (2 * step * start_speed0_);
    if (!(Eigen::Map<const Eigen::VectorXd>(win.speed_gain.data(), static_cast<Eigen::Index>(lo.size())).squaredNorm() >
          0)) {
      win.speed_gain.clear();  // no residual depends on it (all held at 0)
    }
  });
}

int Problem::window_nuisances() const {
  int n = 0;
  for (const Window& w : windows_) n += !w.speed_gain.empty();
  return n;
}

bool Problem::Replay(int w, const std::vector<double>& values, double speed_ratio, Workspace& ws, double* r,
                     double* predicted) const {
  Apply(values, ws);
  const Window& win = windows_[w];
  const Log& log = logs_[win.log];
  const mjModel* m = ws.model.get();
  mjData* d = ws.data.get();
  mj_resetData(m, d);
  std::copy(qpos_init_.begin(), qpos_init_.end(), d->qpos);
  if (start_counter_ >= 0) {
    // the rest of the scene in its initial motion, at the window's speed (the arms' joints are
    // set next)
    for (int i = 0; i < m->nv; ++i) d->qvel[i] = qvel_init_[i] * speed_ratio;
  }
  for (std::size_t j = 0; j < joints_.size(); ++j) {
    d->qpos[joints_[j].qpos] = TrueState(win.q0, static_cast<int>(j), false, values);
    d->qvel[joints_[j].dof] = TrueState(win.qd0, static_cast<int>(j), true, values);
  }
  if (reference_) StartServos(win, ws);
  ws.contacts = 0;
  const int columns = static_cast<int>(columns_.size());
  // the JR3 filters settled on the model's load at the start (the first period's torques
  // applied: the load includes the tool's acceleration)
  const bool wrench = wrench_columns_ > 0;  // nothing else reads the sensors
  if (wrench) {
    for (std::size_t j = 0; j < joints_.size(); ++j)
      d->ctrl[joints_[j].actuator] = log.tau(win.first + 1, static_cast<int>(j));
    mj_forward(m, d);
    ws.wrench.resize(wrenches_.size());
    for (std::size_t i = 0; i < wrenches_.size(); ++i) {
      const WrenchSensor& w = wrenches_[i];
      sensors::Reset(*w.model, ws.wrench[i],
                     sensors::LoadFromMujocoSensor(d->sensordata + w.force_adr, d->sensordata + w.torque_adr));
      // the slower stages update every 4^(k-1) samples counted from the sensor's start: the
      // lab's JR3 starts at time 0, so the row's time gives the phase of that decimation
      ws.wrench[i].sample_count = static_cast<std::uint64_t>(std::max(
          0.0, std::round((log.time[win.first] - run_in_steps_ * m->opt.timestep) * w.model->sample_rate_hz())));
    }
  }
  // one physics step with the inputs set, the JR3 fed the load held over it (computed at its
  // start), as the device feeds it
  auto step = [&]() {
    if (reference_) {
      StepWithServos(ws);
    } else {
      mj_step(m, d);
    }
    ws.contacts = std::max(ws.contacts, d->ncon);
    for (std::size_t i = 0; wrench && i < wrenches_.size(); ++i) {
      const WrenchSensor& w = wrenches_[i];
      sensors::WrenchReading flags;
      sensors::Advance(*w.model, ws.wrench[i],
                       sensors::LoadFromMujocoSensor(d->sensordata + w.force_adr, d->sensordata + w.torque_adr),
                       m->opt.timestep, &flags);
    }
  };
  auto diverged = [&]() {
    return d->warning[mjWARN_BADQPOS].number > 0 || d->warning[mjWARN_BADQVEL].number > 0 ||
           d->warning[mjWARN_BADQACC].number > 0;
  };
  if (run_in_steps_ > 0) {
    // spec run_in: the scene runs in from the start state, the first row's inputs held (the
    // servos hold the command in force), so that what the log does not hold (a rotor's phase
    // and the wrist's sway under its couple) settles on the model's own dynamics; then the rest
    // of the scene's motion is scaled back to the window's start speed, and the window begins
    if (!reference_) {
      for (std::size_t j = 0; j < joints_.size(); ++j)
        d->ctrl[joints_[j].actuator] = log.tau(win.first + 1, static_cast<int>(j));
    }
    for (int s = 0; s < run_in_steps_; ++s) step();
    if (diverged()) return false;
    const double now = d->qvel[counters_[start_counter_].dof];
    const double ratio = qvel_init_[counters_[start_counter_].dof] * speed_ratio / now;
    if (!std::isfinite(ratio)) return false;
    for (int i = 0; i < m->nv; ++i) {
      if (!arm_dof_[i]) d->qvel[i] *= ratio;
    }
  }
  // the model's value and rate of each column at each row (row 0: the start), for the delays;
  // a counter's joint angle; a derived column's parts
  ws.trace.assign(static_cast<std::size_t>(win.rows + 1) * columns * 2, 0.0);
  ws.parts.assign(static_cast<std::size_t>(win.rows + 1) * part_count_, 0.0);
  auto record = [&](int k) {
    for (int c = 0; c < columns; ++c) {
      const Column& col = columns_[c];
      double* at = &ws.trace[(static_cast<std::size_t>(k) * columns + c) * 2];
      for (std::size_t i = 0; i < col.parts.size(); ++i) {
        ws.parts[static_cast<std::size_t>(k) * part_count_ + col.part + i] = ColumnValue(col.parts[i], ws);
      }
      if (!col.parts.empty()) continue;
      at[0] = ColumnValue(col, ws);
      // its rate, for a delay (only an arm's q or qd column has one)
      if (col.joint >= 0 && !col.torque)
        at[1] = col.velocity ? d->qacc[joints_[col.joint].dof] : d->qvel[joints_[col.joint].dof];
    }
  };
  for (const Column& c : columns_) {
    if (c.delay >= 0 && c.velocity) {
      mj_forward(m, d);  // the start's accelerations, the rate of a delayed qd column
      break;
    }
  }
  record(0);
  for (int k = 1; k <= win.rows; ++k) {
    const int row = win.first + k;
    if (reference_) {
      // the row's commands, taken at the start of its period; the servos act at every step
      CommandServos(log, row, ws);
    } else {
      for (std::size_t j = 0; j < joints_.size(); ++j) d->ctrl[joints_[j].actuator] = log.tau(row, static_cast<int>(j));
    }
    for (int s = 0; s < steps_per_row_; ++s) step();
    if (diverged()) return false;
    record(k);
  }
  const double period = steps_per_row_ * m->opt.timestep;
  for (int k = 1; k <= win.rows; ++k) {
    const int row = win.first + k;
    for (int c = 0; c < columns; ++c) {
      const Column& col = columns_[c];
      auto at = [&](int i) { return &ws.trace[(static_cast<std::size_t>(i) * columns + c) * 2]; };
      double y = at(k)[0];
      if (col.counter >= 0) {
        // the device's reading in force at the row: the turns over its gate, if the window saw
        // the gate begin
        const int reading = log.reading[col.counter][row] - win.first;
        const int gate = log.gate[col.counter][row] - win.first;
        y = gate >= 0 ? (at(reading)[0] - at(gate)[0]) / (log.time[win.first + reading] - log.time[win.first + gate]) *
                            lab::kRpmPerRadPerSecond
                      : std::numeric_limits<double>::quiet_NaN();  // (fit.csv: none)
      } else if (!col.parts.empty()) {
        const int n_parts = static_cast<int>(col.parts.size());
        const Eigen::Map<const Eigen::VectorXd> now(&ws.parts[static_cast<std::size_t>(k) * part_count_ + col.part],
                                                    n_parts);
        const Eigen::Map<const Eigen::VectorXd> before(
            &ws.parts[static_cast<std::size_t>(k - 1) * part_count_ + col.part], n_parts);
        y = DerivedValue(now, before, col.rate, period);
      }
      if (col.delay >= 0) {
        // the value x rows earlier: cubic Hermite between the rows around it (value and rate),
        // smooth in the delay; before the window, along the start's rate
        const double x = values[col.delay] / period;
        const double s = k - x;
        if (s <= 0) {
          y = at(0)[0] + at(0)[1] * s * period;
        } else {
          const int i = std::min(static_cast<int>(std::floor(s)), win.rows - 1);
          const double f = s - i, f2 = f * f, f3 = f2 * f;
          const double* a = at(i);
          const double* b = at(i + 1);
          y = (2 * f3 - 3 * f2 + 1) * a[0] + (f3 - 2 * f2 + f) * period * a[1] + (-2 * f3 + 3 * f2) * b[0] +
              (f3 - f2) * period * b[1];
        }
      }
      if (col.gain >= 0) y *= values[col.gain];
      if (col.bias >= 0) y += values[col.bias];
      const int i = (k - 1) * columns + c;
      if (predicted) predicted[i] = y;
      r[i] = Counted(win, col, k) ? weights_[c] * (y - log.measured(row, c)) : 0.0;
    }
  }
  return true;
}

double Problem::ColumnValue(const Column& c, const Workspace& ws) const {
  const mjData* d = ws.data.get();
  if (c.wrench >= 0) return sensors::ReadSelected(*wrenches_[c.wrench].model, ws.wrench[c.wrench])[c.axis];
  if (c.counter >= 0) return d->qpos[counters_[c.counter].qpos];
  const Joint& joint = joints_[c.joint];
  if (c.torque) return d->ctrl[joint.actuator];  // what the servo applied over the last step
  return c.velocity ? d->qvel[joint.dof] : d->qpos[joint.qpos];
}

Problem::Sample Problem::WindowRow(int w, int k) const {
  const Window& win = windows_[w];
  return {win.log, logs_[win.log].time[win.first + k]};
}

double Problem::Measured(int w, int k, int column) const {
  const Window& win = windows_[w];
  return logs_[win.log].measured(win.first + k, column);
}

}  // namespace vlab::identify
