// head_track: the 7-DOF humanoid head follows a red ball with both eyes, an
// external program that talks to the head (an arm device) and to the two eye
// cameras (camera devices) only through the vlab client library.
//
//   head_track --arm HOST:PORT --left HOST:PORT --right HOST:PORT [--quiet]
//
// Each eye's image is searched for the ball by colour (head_track_eyes.h);
// the eye angles that would fixate it, taken at the time of the image, give a
// gaze direction per eye (azimuth = neck yaw - pan, elevation = neck pitch +
// head tilt - eye tilt), tracked with an alpha-beta filter (angle and rate)
// and predicted to the time of each state. Velocity commands, every period:
//   eyes   pan_e = neck_yaw - azimuth_e, common tilt = pitch + head tilt -
//          mean elevation; rate feed-forward + K_eye (target - q)
//   neck   yaw toward the mean azimuth, pitch and head tilt share the mean
//          elevation, roll to 0; rate feed-forward + K_neck (target - q)
// so the neck carries the gaze and the eyes fixate and converge quickly.
//
// Time is the states' simulated time. The frame used with the state of time t
// is the newest one the lab has certainly sent before that state
// (NewestSentFrame); the program waits for it when it has not arrived, so a
// lockstep run repeats bit for bit (the rule assumes frames stamped with the
// lab's simulated time). It exits 0 when the devices stop sending
// (the run is over) or on SIGTERM/SIGINT, 2 on bad arguments or a bridge error.
// Output: one summary line per eye: frames used, frames with the ball, the
// largest distance of the ball from the image centre after 1 s (px).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <future>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bridge/bridge_camera_client.h"
#include "bridge/bridge_client.h"
#include "bridge/bridge_program.h"
#include "head_track_eyes.h"

namespace {

using vlab::bridge::Arm;
using vlab::bridge::ArmMode;
using vlab::bridge::CameraClient;

using vlab::bridge::program::Address;
using vlab::bridge::program::ParseAddress;
using vlab::bridge::program::Stopped;

constexpr double kReadTimeout_s = 2.0;       // no state for this long: the run is over
constexpr double kFrameTimeout_s = 1.0;      // wait for a frame the lab has sent
constexpr double kSlice_s = 0.05;            // waits are cut into slices to see SIGTERM
constexpr double kEyeGain = 25.0;            // 1/s
constexpr double kNeckGain = 3.0;            // 1/s
constexpr double kAlpha = 0.7, kBeta = 0.3;  // alpha-beta filter of the gaze angles
constexpr double kGap_s = 0.5;               // the ball unseen this long: restart, stop predicting
constexpr const char* kJoints[7] = {"neck_pitch", "neck_roll",    "neck_yaw",     "head_tilt",
                                    "eye_tilt",   "left_eye_pan", "right_eye_pan"};
enum Joint { kNeckPitch, kNeckRoll, kNeckYaw, kHeadTilt, kEyeTilt, kLeftPan, kRightPan };

struct Options {
  Address arm, left, right;
  bool quiet = false;
};

bool ParseOptions(int argc, char** argv, Options* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--quiet") {
      o->quiet = true;
      continue;
    }
    if (i + 1 >= argc) return false;
    Address* target = arg == "--arm" ? &o->arm : arg == "--left" ? &o->left : arg == "--right" ? &o->right : nullptr;
    if (!target || !ParseAddress(argv[++i], target)) return false;
  }
  return o->arm.port > 0 && o->left.port > 0 && o->right.port > 0;
}

// One eye: its camera, the frames received but not used yet, its gaze estimate.
struct Eye {
  Eye(const char* n, int pan, CameraClient c) : name(n), pan_joint(pan), camera(std::move(c)) {}
  const char* name;
  int pan_joint;
  CameraClient camera;
  head_track::FrameSchedule schedule;
  head_track::Intrinsics k;
  std::deque<CameraClient::Frame> queue;  // received, in increasing id
  std::int64_t used = -1;                 // id of the last frame used
  // the gaze direction toward the ball: azimuth (left +), elevation (up +), rad
  head_track::AngleFilter azimuth{kAlpha, kBeta, kGap_s}, elevation{kAlpha, kBeta, kGap_s};
  // statistics
  long frames = 0, found = 0, late = 0;
  double max_offset_px = 0;
};

Eye MakeEye(const char* name, int pan_joint, CameraClient camera, double control_period_s) {
  Eye e(name, pan_joint, std::move(camera));
  const nlohmann::json& d = e.camera.describe();
  e.schedule.fps = e.camera.fps();
  e.schedule.exposure_s = d.value("exposure_s", 0.0);
  e.schedule.latency_s = d.value("latency_s", 0.0);
  e.schedule.control_period_s = control_period_s;
  const auto& c = e.camera.calibration();
  e.k = {c.fx, c.fy, c.cx, c.cy};
  return e;
}

// The frame to use with the state of time t: the newest one up to the newest
// the lab has sent (waited for if missing); nullptr when there is none or it
// was used already.
const CameraClient::Frame* NextFrame(Eye& e, double t) {
  const std::int64_t newest = head_track::NewestSentFrame(t, e.schedule);
  if (newest < 1) return nullptr;  // frame 0 may predate the subscription
  double waited = 0;
  while ((e.queue.empty() || e.queue.back().id < newest) && !Stopped()) {
    if (waited >= kFrameTimeout_s) {
      ++e.late;
      break;
    }
    CameraClient::Frame f;
    try {
      e.camera.Receive(kSlice_s, &f);
    } catch (const vlab::bridge::TimeoutError&) {
      waited += kSlice_s;
      continue;
    }
    e.queue.push_back(std::move(f));
  }
  while (e.queue.size() > 1 && e.queue[1].id <= newest) e.queue.pop_front();
  if (e.queue.empty() || e.queue.front().id > newest || e.queue.front().id <= e.used) return nullptr;
  e.used = e.queue.front().id;
  return &e.queue.front();
}

// Joint positions at time t from the recent states (the nearest one).
const Eigen::VectorXd& PositionsAt(const std::deque<Arm::State>& history, double t) {
  const Arm::State* best = &history.back();
  for (const Arm::State& s : history) {
    if (std::abs(s.time - t) < std::abs(best->time - t)) best = &s;
  }
  return best->q;
}

// A new image: where the ball is, as a gaze direction, into the eye's filter.
void Measure(Eye& e, const CameraClient::Frame& f, const Eigen::VectorXd& q_f) {
  ++e.frames;
  const head_track::Blob blob = head_track::FindBall(f.rgb.data(), f.width, f.height);
  if (!blob.found) return;
  ++e.found;
  if (f.time_s >= 1.0) e.max_offset_px = std::max(e.max_offset_px, std::hypot(blob.u - e.k.cx, blob.v - e.k.cy));
  const head_track::EyeAngles a = head_track::FixateAngles(blob.u, blob.v, e.k, q_f[e.pan_joint], q_f[kEyeTilt]);
  e.azimuth.Update(f.time_s, q_f[kNeckYaw] - a.pan);
  e.elevation.Update(f.time_s, q_f[kNeckPitch] + q_f[kHeadTilt] - a.tilt);
}

// Velocity commands for the state `s` from both eyes' estimates.
Eigen::VectorXd Command(const Eye& l, const Eye& r, const Arm::State& s, const Arm& arm) {
  const Eigen::VectorXd& q = s.q;
  Eigen::VectorXd v = Eigen::VectorXd::Zero(7);
  // each eye that has seen the ball: its pan on its own azimuth, predicted to now
  double az = 0, el = 0, az_rate = 0, el_rate = 0;  // sums, then means
  int n = 0;
  for (const Eye* e : {&l, &r}) {
    if (!e->azimuth.valid()) continue;
    const double a = e->azimuth.Angle(s.time), a_rate = e->azimuth.Rate(s.time);
    const double pan = q[kNeckYaw] - a;
    v[e->pan_joint] = s.qd[kNeckYaw] - a_rate + kEyeGain * (pan - q[e->pan_joint]);
    az += a;
    az_rate += a_rate;
    el += e->elevation.Angle(s.time);
    el_rate += e->elevation.Rate(s.time);
    ++n;
  }
  const double w = n == 2 ? 0.5 : 1.0;
  az *= w, el *= w, az_rate *= w, el_rate *= w;
  // the common eye tilt on the mean elevation
  if (n) {
    const double tilt = q[kNeckPitch] + q[kHeadTilt] - el;
    v[kEyeTilt] = s.qd[kNeckPitch] + s.qd[kHeadTilt] - el_rate + kEyeGain * (tilt - q[kEyeTilt]);
  }
  // the neck: toward the mean gaze (the rest pose while no eye has seen the ball)
  v[kNeckYaw] = az_rate + kNeckGain * (az - q[kNeckYaw]);
  v[kNeckPitch] = 0.5 * el_rate + kNeckGain * (0.5 * el - q[kNeckPitch]);
  v[kHeadTilt] = 0.5 * el_rate + kNeckGain * (0.5 * el - q[kHeadTilt]);
  v[kNeckRoll] = kNeckGain * (0 - q[kNeckRoll]);
  // stay inside the velocity limits, and stop short of the position limits
  for (int j = 0; j < 7; ++j) {
    if (!arm.velocity_max().empty())
      v[j] = std::clamp(v[j], -0.95 * arm.velocity_max()[j], 0.95 * arm.velocity_max()[j]);
    if (!arm.position_min().empty() && q[j] < arm.position_min()[j] + 0.02) v[j] = std::max(v[j], 0.0);
    if (!arm.position_max().empty() && q[j] > arm.position_max()[j] - 0.02) v[j] = std::min(v[j], 0.0);
  }
  return v;
}

// The next state (lockstep: the next one; realtime: the newest); false when
// none comes within kReadTimeout_s (the run is over) or a signal asks to stop.
bool NextState(Arm& arm, Arm::State* state) {
  for (double waited = 0; waited < kReadTimeout_s && !Stopped(); waited += kSlice_s) {
    try {
      arm.ReadLatest(kSlice_s, state);
      return true;
    } catch (const vlab::bridge::TimeoutError&) {
    }
  }
  return false;
}

// Reorders a command from this program's joint order into the device's.
Eigen::VectorXd ToDevice(const Eigen::VectorXd& v, const std::vector<int>& index) {
  Eigen::VectorXd out(7);
  for (int j = 0; j < 7; ++j) out[index[j]] = v[j];
  return out;
}

int Run(const Options& o) {
  Arm arm = Arm::Connect(o.arm.host, o.arm.port, 5.0);
  std::vector<int> index(7, -1);  // kJoints[j] is device joint index[j]
  for (int j = 0; j < 7; ++j) {
    const auto& names = arm.joint_names();
    const auto it = std::find(names.begin(), names.end(), kJoints[j]);
    if (arm.joints() != 7 || it == names.end()) {
      std::fprintf(stderr, "head_track: %s is not the 7-DOF head (no joint '%s')\n", arm.Label().c_str(), kJoints[j]);
      return 2;
    }
    index[j] = static_cast<int>(it - names.begin());
  }
  const double period = 1.0 / arm.describe().value("rates", nlohmann::json::object()).value("control_hz", 500.0);
  // the cameras answer at the end of a period: connect them while answering the
  // first states with hold commands (the lab then subscribes both at once)
  vlab::bridge::CameraClientOptions co;
  co.timeout_s = 5.0;
  auto left_future =
      std::async(std::launch::async, [&] { return CameraClient::Connect(o.left.host, o.left.port, co); });
  auto right_future =
      std::async(std::launch::async, [&] { return CameraClient::Connect(o.right.host, o.right.port, co); });
  Arm::State state = arm.Read(5.0);
  auto ready = [](auto& f) { return f.wait_for(std::chrono::milliseconds(20)) == std::future_status::ready; };
  while (!(ready(left_future) & ready(right_future))) {
    arm.Write(ArmMode::kHold, Eigen::VectorXd::Zero(7), state.seq);
    arm.Read(kReadTimeout_s, &state);
  }
  Eye left = MakeEye("left", kLeftPan, left_future.get(), period);
  Eye right = MakeEye("right", kRightPan, right_future.get(), period);
  if (!o.quiet)
    std::printf("head_track: %s, %s, %s\n", arm.Label().c_str(), left.camera.Label().c_str(),
                right.camera.Label().c_str());

  // the loop: states in order of seq; the joint history for the images' times
  std::deque<Arm::State> history;
  std::int64_t last_seq = -1;
  long refused = 0;
  for (;;) {
    if (state.seq > last_seq) {
      last_seq = state.seq;
      history.push_back(state);
      if (history.size() > 256) history.pop_front();
      for (Eye* e : {&left, &right}) {
        if (const CameraClient::Frame* f = NextFrame(*e, state.time)) Measure(*e, *f, PositionsAt(history, f->time_s));
      }
      if (state.status & vlab::bridge::kStatusRefused) ++refused;
      arm.Write(ArmMode::kVelocity, ToDevice(Command(left, right, state, arm), index), state.seq);
    }
    if (!NextState(arm, &state)) break;  // the devices stopped sending, or SIGTERM
  }
  for (const Eye* e : {&left, &right}) {
    std::printf("%s eye: %ld frames, ball in %ld, late %ld, largest offset from the centre after 1 s %.2f px\n",
                e->name, e->frames, e->found, e->late, e->max_offset_px);
  }
  if (refused) std::printf("refused commands: %ld periods\n", refused);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  if (!ParseOptions(argc, argv, &options)) {
    std::fprintf(stderr, "usage: %s --arm HOST:PORT --left HOST:PORT --right HOST:PORT [--quiet]\n", argv[0]);
    return 2;
  }
  return vlab::bridge::program::Main("head_track", [&] { return Run(options); });
}
