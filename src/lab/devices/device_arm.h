// Simulated arm device (kind arm): a joint servo interface over MuJoCo motors.
//
// Ports
//   input   ArmCommand (mode hold | position | velocity | torque, one value per
//           joint), taken at the start of a control period; a payload
//           (SetPayload: mass, centre of mass, inertia at the flange), also
//           from the wire (type 6 from the owner, taken with the period's
//           command; the describe reply reports it, whatever servo.feedforward)
//   output  ArmState (q, qd, applied tau, status bits), sampled at the end of
//           every control period; q and qd are the sensed ones (below)
//   rate    the servo runs at every physics step (model timestep); commands and
//           outputs at the control rate
// Start: the `initial` joints (or the keyframe's), moved by a seeded draw within
// `initial_jitter` (from the device's seed, once: every reset starts the same);
// with `initial`, the free bodies welded to the arm (a gripper) are put at
// their welds' poses there (arm_welded.h).
// Behaviour, like a real servo drive:
//   - holds the initial position until the first command arrives;
//   - position and velocity modes run a PD servo per joint with bias (gravity
//     and Coriolis) feed-forward: tau = kp (q_ref - q) + kd (qd_ref - qd) +
//     h(q, qd); velocity mode integrates q_ref from the commanded velocity,
//     position mode feeds forward the command's rate;
//   - h comes from one of two sources (servo.feedforward):
//       world  the world model's bias force at the arm's joints (MuJoCo's
//              qfrc_bias): gravity and Coriolis of everything the arm carries,
//              a gripper, a ball's rotor, a yo-yo included (the default);
//       model  the servo's own model (arm_servo_model.h): the arm's own bodies,
//              the bodies named in servo.bodies and the declared payload, all a
//              real controller knows; anything else is a disturbance the
//              joints feel;
//   - gains follow from the requested bandwidth and damping ratio and each
//     joint's inertia H_ii at the initial pose: kp = H_ii w^2, kd = 2 zeta H_ii w,
//     H_ii of the world model (feedforward world) or of the servo's model with
//     the payload set at start (feedforward model); later payloads keep the gains;
//   - it senses what its encoders give (key sensing, arm_sensing.h): joint
//     positions in whole counts of the resolution and velocities exact or the
//     backward difference of the counts over the physics step; the PD, the
//     state and the log's q and qd columns use the sensed values (no key:
//     exact positions and the integrator's velocities);
//   - the servo reference stays within 0.2 rad of the measured position (a
//     following-error window: a joint blocked by contact does not wind up);
//   - torque mode applies the commanded torque as is;
//   - every torque is clipped to the motor's range (status bit when it is);
//   - a command with the wrong size, a non-finite value, a position outside the
//     joint range, a velocity beyond max_velocity or a torque outside the motor
//     range is refused and counted; the arm keeps its previous command.
// An arm may be driven by another device (a point device, which holds the
// arm's claim: lab_command_writer.h): its commands then come from that device,
// and lockstep does not wait for its own.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <Eigen/Core>

#include "bridge/bridge_messages.h"
#include "lab/devices/arm_sensing.h"
#include "lab/devices/arm_servo_model.h"
#include "lab/devices/arm_welded.h"
#include "lab/devices/device.h"

namespace vlab::lab {

/// Joint servo of a simulated arm: the drive electronics between a command
/// and the motor torque (position and velocity modes).
struct ServoConfig {
  /// Where the servo's bias feed-forward comes from (see SimArm).
  enum class Feedforward { kWorld, kModel };
  double bandwidth_hz = 10.0;  ///< closed-loop natural frequency of each joint servo
  double damping_ratio = 1.0;  ///< its damping ratio
  Feedforward feedforward = Feedforward::kWorld;
  /// Bodies rigidly attached to the arm that the servo's model includes
  /// (besides the bodies that carry the arm's joints), MJCF names.
  std::vector<std::string> bodies;
};

struct ArmParams : DeviceParams {
  std::vector<std::string> joints;     ///< MJCF joint names, in device order
  std::vector<std::string> actuators;  ///< MJCF motor actuators (torque), default: joint names
  std::vector<double> initial;         ///< initial joint positions, rad (default: qpos0)
  /// Seeded start: each joint starts uniform in initial +- this, rad (one value or one per
  /// joint; empty: none). Drawn once from the device's seed; needs `initial`.
  std::vector<double> initial_jitter;
  std::vector<double> max_velocity;  ///< |qd| limits of velocity commands, rad/s (empty: none)
  ServoConfig servo;
  Payload payload;        ///< declared at the flange (the body of the last joint); mass 0: none
  SensingConfig sensing;  ///< encoder resolution and velocity source (empty: exact)
  CommandInputConfig input;
  bool log_following_error = false;  ///< log NAME.following_error: max |q_ref - q| of the servo, rad
  /// log the command in force each period: NAME.cmd_mode (the bridge's ArmMode number) and
  /// NAME.cmd.JOINT (its value: position rad, velocity rad/s, torque N m; hold: the position held)
  bool log_command = false;
};

/// Reads an arm entry's keys (joints, actuators, initial, initial_jitter, max_velocity, servo,
/// payload, sensing, watchdog_periods, owner_timeout, log_following_error, log_command). Throws
/// InputError naming the file, line and key.
std::shared_ptr<const DeviceParams> ReadArmParams(MapReader& r);
/// Makes a SimArm.
std::unique_ptr<Device> MakeArm(const DeviceContext& context, const DeviceConfig& config);

class SimArm final : public Device, public CommandInput, public StepHooks {
 public:
  /// Binds the device to the model's joints and motors and builds the servo's
  /// model. Throws InputError naming the device, its scenario line and the
  /// missing or unsuitable element (a joint, a motor, servo.bodies, payload).
  static std::unique_ptr<SimArm> Create(const DeviceContext& context, const DeviceConfig& config);

  int dof() const { return static_cast<int>(qpos_adr_.size()); }
  const std::vector<std::string>& joint_names() const { return joint_names_; }
  const Eigen::VectorXd& lower_limits() const { return lower_; }
  const Eigen::VectorXd& upper_limits() const { return upper_; }
  /// Motor torque ranges, N m (−inf / +inf where unlimited).
  const Eigen::VectorXd& torque_min() const { return tau_min_; }
  const Eigen::VectorXd& torque_max() const { return tau_max_; }
  /// |qd| limits of velocity commands, rad/s (empty: none).
  const Eigen::VectorXd& max_velocity() const { return max_velocity_; }

  /// Takes a command. Returns false (and counts it) when refused.
  bool Command(const bridge::ArmCommand& command);
  /// The state of the last Sample() (or of the reset).
  const bridge::ArmState& state() const { return state_; }
  /// Samples the device output into `state`.
  void Sample(const mjData& data, double time_s, bridge::ArmState* state) const;
  /// Marks the arm as driven by the device `driver` (the lab does, once the
  /// claim table gave that device the arm's command input): lockstep then does
  /// not wait for the arm's own clients.
  void set_driver(const std::string& driver) { driver_ = driver; }
  const std::string& driver() const { return driver_; }

  /// Declares the payload at the flange (frame: the body of the last joint):
  /// the servo's model carries it from the next physics step (feedforward
  /// model; with world it is kept but the world's bias force is used). Returns
  /// false, keeping the previous payload, when it is not a rigid body
  /// (CheckPayload), with "FIELD: REASON" in `why` if given. Never throws.
  bool SetPayload(const Payload& payload, std::string* why = nullptr);
  const Payload& payload() const { return servo_model_->payload(); }
  ServoConfig::Feedforward feedforward() const { return feedforward_kind_; }
  /// The servo's own model (built for either feed-forward).
  const ArmServoModel& servo_model() const { return *servo_model_; }
  /// The joints' encoders (disabled without the key sensing).
  const JointSensing& sensing() const { return sensing_; }

  long refused_commands() const { return refused_; }
  const Eigen::VectorXd& kp() const { return kp_; }
  const Eigen::VectorXd& kd() const { return kd_; }
  double bandwidth_hz() const { return bandwidth_hz_; }
  double damping_ratio() const { return damping_ratio_; }
  /// Sets the servo's bandwidth (Hz, > 0) and damping ratio (> 0); the gains follow from them
  /// at the next Start, as from the config's.
  void Tune(double bandwidth_hz, double damping_ratio) {
    bandwidth_hz_ = bandwidth_hz;
    damping_ratio_ = damping_ratio;
  }
  /// Takes up the servo at `d`'s state as the end of a control period left it (a replay that
  /// starts mid-run; gains as the last Start made them): holding `q_ref` with no rate, no
  /// position command before, and the encoders' last reading (sensing) that of the physics
  /// step before, the joints at q - qd dt. Commands then follow as in a run.
  void Resume(const mjData& d, const Eigen::VectorXd& q_ref);

  // Device; CommandInput (a typed command: TakeCommand); StepHooks (the servo)
  void SetInitialState(mjData& d) const override;
  void Start(mjData& d) override;
  void Reset(const mjData& d) override;
  void Actuate(mjData& d, double dt) override;
  void Sample(const mjData& d, double t) override;
  /// Log columns: NAME.q.JOINT, NAME.qd.JOINT (sensed), NAME.tau.JOINT,
  /// NAME.limit_violation (of the true q), NAME.following_error (largest
  /// |q_ref - q| of the servo, sensed q, rad) when configured, and the command in
  /// force (log_command): NAME.cmd_mode and NAME.cmd.JOINT.
  std::vector<std::string> Columns() const override;
  int ColumnCount() const override {
    return 3 * dof() + 1 + (log_following_error_ ? 1 : 0) + (log_command_ ? 1 + dof() : 0);
  }
  void Row(const mjData& d, double* out) const override;
  int log_rank() const override { return 0; }
  void EncodeState(double seq, double t, std::uint32_t endpoint_bits, std::vector<double>* scratch,
                   std::vector<unsigned char>* out) const override;
  void ConfigureEndpoint(double control_hz, bridge::EndpointConfig* config) const override;
  std::string DescribeJson(const bridge::DeviceDescription& common) const override;
  CommandRole command_role() const override {
    return driver_.empty() ? CommandRole::kWaitedFromStart : CommandRole::kDriven;
  }
  bool TakeCommand(bridge::DeviceEndpoint& endpoint, std::vector<double>* scratch) override;
  void Hold() override;
  int watchdog_periods() const override { return watchdog_periods_; }
  double owner_timeout_s() const override { return owner_timeout_s_; }

 private:
  explicit SimArm(const DeviceConfig& config) : Device(config) {
    capabilities_.command_input = this;
    capabilities_.step_hooks = this;
    capabilities_.arm = this;
  }

  // the joints' true state into q_true_, qd_true_
  void Gather(const mjData& d) const;
  // the encoders read the state a step dt after their last reading
  void Sense(const mjData& d, double dt);
  // what the encoders would read now (sensed q and qd), keeping nothing
  void Peek(const mjData& d, double* q, double* qd) const;

  const mjModel* model_ = nullptr;
  std::vector<std::string> joint_names_;
  std::vector<int> qpos_adr_, dof_adr_, actuator_ids_;
  Eigen::VectorXd lower_, upper_, tau_min_, tau_max_, initial_, max_velocity_;
  ArmWelds welds_;  // free bodies welded to the arm (a gripper): placed with the initial joints
  int watchdog_periods_ = 3;
  double owner_timeout_s_ = 1.0;
  bool has_initial_ = false;
  bool log_following_error_ = false;
  bool log_command_ = false;
  double bandwidth_hz_ = 10.0, damping_ratio_ = 1.0;
  Eigen::VectorXd kp_, kd_;
  ServoConfig::Feedforward feedforward_kind_ = ServoConfig::Feedforward::kWorld;
  std::unique_ptr<ArmServoModel> servo_model_;
  Eigen::VectorXd feedforward_;  // the servo model's bias torques of this step
  JointSensing sensing_;
  mutable Eigen::VectorXd q_true_, qd_true_;  // the joints' true state, gathered for sensing
  std::string driver_;                        // the device that drives it ("": none)
  // servo state
  bridge::ArmMode mode_ = bridge::ArmMode::kHold;
  Eigen::VectorXd value_, q_ref_, qd_ref_, last_position_command_, tau_;
  bool have_position_command_ = false;
  bool saturated_ = false;
  double command_period_s_ = 0.0;
  long refused_ = 0;
  bool last_refused_ = false;
  bridge::ArmState state_;
  // wire scratch, sized at creation
  mutable bridge::ArmStateMsg message_;
  bridge::ArmCommandMsg wire_command_;
  bridge::ArmCommand command_;
};

}  // namespace vlab::lab
