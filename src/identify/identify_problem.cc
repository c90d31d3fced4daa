#include "identify/identify_problem.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/QR>

#include "core/core_errors.h"
#include "lab/devices/device_arm.h"
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

}  // namespace

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

std::unique_ptr<Problem> Problem::Create(const Spec& spec) {
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
  p->BindJoints(scenario);
  p->BindWrenches(scenario);
  p->BindColumns();
  p->BindParameters();
  p->ReadLogs();
  p->CutWindows();
  if (spec.skip_contacts) p->SkipContactWindows();
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
  for (const ColumnSpec& c : spec_.columns) {
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
    for (std::size_t c = 0; c < columns_.size(); ++c) fitted[c] = column(column_names_[c]);
    for (int r = 0; r < rows; ++r) {
      const std::vector<double>& row = table.rows[r];
      log.time.push_back(row[time]);
      for (int j = 0; j < n; ++j) {
        log.q(r, j) = row[q[j]];
        log.qd(r, j) = row[qd[j]];
        log.tau(r, j) = row[tau[j]];
      }
      for (std::size_t c = 0; c < columns_.size(); ++c) log.measured(r, static_cast<int>(c)) = row[fitted[c]];
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
    if (reference_) ReadCommands(table, file, steps_per_row_, &log);
    logs_.push_back(std::move(log));
  }
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
    const int n = static_cast<int>(logs_[l].time.size());
    int first = 0;
    for (; first + rows < n; first += rows) {
      Window w{static_cast<int>(l), first, rows, residual_count_, {}, {}};
      w.q0 = QuadraticAbout(logs_[l].q, first, spec_.start_smoothing);
      w.qd0 = QuadraticAbout(logs_[l].qd, first, spec_.start_smoothing);
      windows_.push_back(w);
      residual_count_ += rows * columns;
    }
    rows_left_out_ += n - 1 - first;
  }
  if (windows_.empty()) {
    throw InputError(spec_.where_window + ": " + std::to_string(spec_.window_s) + " s is longer than every log");
  }
}

void Problem::SkipContactWindows() {
  std::vector<double> nominal;
  for (const BoundParameter& p : parameters_) nominal.push_back(p.nominal);
  Workspace ws = MakeWorkspace();
  std::vector<Window> kept;
  residual_count_ = 0;
  // a contact the recording went through shows in its recorded states, one the nominal model
  // would make in its replay
  auto recorded_contact = [&](const Window& win) {
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
  for (int w = 0; w < window_count(); ++w) {
    std::vector<double> r(window_residuals(w));
    const bool ok = Rollout(w, nominal, ws, r.data(), nullptr);
    if (!ok || ws.contacts > 0 || recorded_contact(windows_[w])) {
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
      inertia[k] = e.inertia0[k];
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
  Apply(values, ws);
  const Window& win = windows_[w];
  const Log& log = logs_[win.log];
  const mjModel* m = ws.model.get();
  mjData* d = ws.data.get();
  mj_resetData(m, d);
  std::copy(qpos_init_.begin(), qpos_init_.end(), d->qpos);
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
      ws.wrench[i].sample_count =
          static_cast<std::uint64_t>(std::max(0.0, std::round(log.time[win.first] * w.model->sample_rate_hz())));
    }
  }
  // the model's value and rate of each column at each row (row 0: the start), for the delays
  ws.trace.assign(static_cast<std::size_t>(win.rows + 1) * columns * 2, 0.0);
  auto record = [&](int k) {
    for (int c = 0; c < columns; ++c) {
      double* at = &ws.trace[(static_cast<std::size_t>(k) * columns + c) * 2];
      if (columns_[c].wrench >= 0) {
        const int w = columns_[c].wrench;
        at[0] = sensors::ReadSelected(*wrenches_[w].model, ws.wrench[w])[columns_[c].axis];
        continue;  // its rate: no delay on a wrench column
      }
      const Joint& joint = joints_[columns_[c].joint];
      if (columns_[c].torque) {  // what the servo applied over the last step (no delay: no rate)
        at[0] = d->ctrl[joint.actuator];
        at[1] = 0;
        continue;
      }
      at[0] = columns_[c].velocity ? d->qvel[joint.dof] : d->qpos[joint.qpos];
      at[1] = columns_[c].velocity ? d->qacc[joint.dof] : d->qvel[joint.dof];
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
    for (int s = 0; s < steps_per_row_; ++s) {
      if (reference_) {
        StepWithServos(ws);
      } else {
        mj_step(m, d);
      }
      ws.contacts = std::max(ws.contacts, d->ncon);
      // the load held over the step just taken (computed at its start), as the device feeds it
      for (std::size_t i = 0; wrench && i < wrenches_.size(); ++i) {
        const WrenchSensor& w = wrenches_[i];
        sensors::WrenchReading flags;
        sensors::Advance(*w.model, ws.wrench[i],
                         sensors::LoadFromMujocoSensor(d->sensordata + w.force_adr, d->sensordata + w.torque_adr),
                         m->opt.timestep, &flags);
      }
    }
    if (d->warning[mjWARN_BADQPOS].number > 0 || d->warning[mjWARN_BADQVEL].number > 0 ||
        d->warning[mjWARN_BADQACC].number > 0) {
      return false;
    }
    record(k);
  }
  const double period = steps_per_row_ * m->opt.timestep;
  for (int k = 1; k <= win.rows; ++k) {
    const int row = win.first + k;
    for (int c = 0; c < columns; ++c) {
      const Column& col = columns_[c];
      auto at = [&](int i) { return &ws.trace[(static_cast<std::size_t>(i) * columns + c) * 2]; };
      double y = at(k)[0];
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
      // a wrench column's first rows: the filter's state there is not known (CutWindows)
      const bool settling = col.wrench >= 0 && k <= wrench_settle_rows_;
      r[i] = settling ? 0.0 : weights_[c] * (y - log.measured(row, c));
    }
  }
  return true;
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
