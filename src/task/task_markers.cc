#include "task/task_markers.h"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <thread>

#include "core/core_errors.h"
#include "task/task_udp.h"

namespace vlab::task {

namespace {

constexpr double kSameTime_s = 1e-9;  // the camera's own tolerance (device_camera.cc)
constexpr double kMatch_s = 1e-6;     // a state's time against a wanted time
constexpr double kRenew_s = 3.0;      // subscriptions lapse after 10 s of silence

// frames with a stamp <= t (+ tolerance): the camera's CountUpTo (sensor_camera.cc)
std::int64_t FramesUpTo(double t, double fps, double offset) {
  const double x = (t + kSameTime_s - offset) * fps;
  return x < 0 ? 0 : static_cast<std::int64_t>(std::floor(x)) + 1;
}

// the first period boundary k * period (k >= 0) at or after t (tolerance as the camera's)
double BoundaryAtOrAfter(double t, double period_s) {
  const double k = std::ceil((t - kSameTime_s) / period_s - 1e-9);
  return std::max(0.0, k) * period_s;
}

}  // namespace

double MarkersFrameDue(const CameraTiming& timing, double period_s, double t0, double* frame_time_s) {
  const double offset = 0.5 * timing.exposure_s;
  // frames rendered at boundaries up to t0 - period have stamps <= t0 - period;
  // the first one after them is the first reported at or after t0
  const std::int64_t i = FramesUpTo(t0 - period_s, timing.fps, offset);
  const double stamp = static_cast<double>(i) / timing.fps + offset;
  const double frame_time = BoundaryAtOrAfter(stamp, period_s);
  if (frame_time_s) *frame_time_s = frame_time;
  return BoundaryAtOrAfter(frame_time + timing.latency_s, period_s);
}

UdpMarkers::UdpMarkers(const std::string& name, const std::string& endpoint, double timeout_s)
    : name_(name), timeout_s_(timeout_s) {
  SplitEndpoint(endpoint, "markers '" + (name.empty() ? std::string("?") : name) + "'", &host_, &port_);
  if (!(timeout_s > 0)) throw InputError("markers: the connect timeout must be > 0 s");
}

UdpMarkers::~UdpMarkers() = default;

void UdpMarkers::Open() {
  if (client_) return;
  // the vision program may still be connecting to its camera: retry until the timeout
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s_);
  while (true) {
    try {
      client_.emplace(bridge::MarkersClient::Connect(host_, port_, std::min(1.0, timeout_s_)));
      break;
    } catch (const bridge::ProtocolError&) {
      throw;
    } catch (const bridge::BridgeError& e) {
      if (std::chrono::steady_clock::now() >= deadline) {
        char s[32];
        std::snprintf(s, sizeof s, "%g", timeout_s_);
        throw bridge::TimeoutError("markers device " + host_ + ":" + std::to_string(port_) + " did not answer within " +
                                   s + " s (" + e.what() + ")");
      }
      // meanwhile the lab serves its devices (the vision program may be connecting to its camera)
      for (int i = 0; i < 20; ++i) {
        if (idle_) idle_();
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
    }
  }
  if (name_.empty()) name_ = client_->name();
  const nlohmann::json& camera = client_->describe().value("camera", nlohmann::json::object());
  if (camera.is_object()) {
    const auto number = [&camera](const char* key) {
      const nlohmann::json& v = camera.value(key, nlohmann::json());
      return v.is_number() ? v.get<double>() : -1.0;
    };
    const double fps = number("fps"), exposure = number("exposure_s"), latency = number("latency_s");
    if (fps > 0 && exposure >= 0 && latency >= 0) timing_ = {fps, exposure, latency};
  }
  renewed_ = std::chrono::steady_clock::now();
}

void UdpMarkers::Renew() {
  Open();
  client_->KeepAlive();
  renewed_ = std::chrono::steady_clock::now();
}

void UdpMarkers::KeepAliveNowAndThen() {
  const auto now = std::chrono::steady_clock::now();
  if (std::chrono::duration<double>(now - renewed_).count() < kRenew_s) return;
  client_->KeepAlive();
  renewed_ = now;
}

bool UdpMarkers::Next(double timeout_s, bridge::MarkersClient::State* out) {
  Open();
  KeepAliveNowAndThen();
  try {
    *out = client_->Read(timeout_s);
  } catch (const bridge::TimeoutError&) {
    return false;
  }
  out->time -= origin_s_;
  newest_ = *out;
  have_ = true;
  return true;
}

bool UdpMarkers::Latest(bridge::MarkersClient::State* out) {
  bridge::MarkersClient::State s;
  while (Next(0.0, &s)) {
  }
  if (have_) *out = newest_;
  return have_;
}

bool UdpMarkers::Poll(double t_min, bridge::MarkersClient::State* out) {
  bridge::MarkersClient::State s;
  while (Next(0.0, &s)) {
    if (s.time >= t_min - kMatch_s) {
      *out = std::move(s);
      return true;
    }
  }
  return false;
}

bool UdpMarkers::WaitFor(double t_min, double timeout_s, bridge::MarkersClient::State* out) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  bridge::MarkersClient::State s;
  while (true) {
    const double left = std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0) return false;
    if (idle_) idle_();  // (in process: the lab's devices answer their clients meanwhile)
    if (!Next(std::min(left, idle_ ? 0.005 : 1.0), &s)) continue;
    if (s.time >= t_min - kMatch_s) {
      *out = std::move(s);
      return true;
    }
  }
}

}  // namespace vlab::task
