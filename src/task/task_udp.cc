#include "task/task_udp.h"

#include <nlohmann/json.hpp>

#include "bridge/bridge_client_device.h"
#include "bridge/bridge_layouts.h"
#include "core/core_errors.h"
#include "task/task_markers.h"

namespace vlab::task {

namespace {

// how long a payload waits for the arm's answer, s (a lockstep lab answers while it waits for the command)
constexpr double kPayloadTimeout_s = 2.0;

class UdpArm final : public Channel {
 public:
  explicit UdpArm(bridge::Arm arm) : arm_(std::move(arm)) {
    const nlohmann::json& layout = arm_.describe().value("layout", nlohmann::json::object());
    state_names_ = bridge::ExpandLayoutFields(layout.value("state", nlohmann::json::array()), arm_.Label());
    command_names_ = bridge::ExpandLayoutFields(layout.value("command", nlohmann::json::array()), arm_.Label());
  }
  const std::string& name() const override { return arm_.name(); }
  bridge::DeviceKind kind() const override { return bridge::DeviceKind::kArm; }
  const std::vector<std::string>& state_names() const override { return state_names_; }
  const std::vector<std::string>& command_names() const override { return command_names_; }
  std::vector<std::string> joint_names() const override { return arm_.joint_names(); }
  // the describe reply's limits.velocity_max (empty: the device gives none, the defaults apply)
  std::vector<double> velocity_limits() const override { return arm_.velocity_max(); }
  bool Read(std::vector<double>* v) override {
    if (!have_) return false;
    const int n = arm_.joints();
    v->assign(1 + 3 * n, 0.0);
    (*v)[0] = state_.status;
    for (int i = 0; i < n; ++i) {
      (*v)[1 + i] = state_.q[i];
      (*v)[1 + n + i] = state_.qd[i];
      (*v)[1 + 2 * n + i] = state_.tau[i];
    }
    return true;
  }
  bool Write(const std::vector<double>& v, std::string* why) override {
    if (!have_) {
      *why = "no state to answer yet";
      return false;
    }
    values_ = Eigen::Map<const Eigen::VectorXd>(v.data() + 1, static_cast<long>(v.size()) - 1);
    if (!arm_.Write(static_cast<bridge::ArmMode>(static_cast<int>(v[0])), values_, state_.seq)) {
      *why = "the datagram could not be sent";
      return false;
    }
    return true;
  }
  bool SetPayload(const bridge::ArmPayloadMsg& payload, std::string* why) override {
    try {
      arm_.SetPayload(payload, kPayloadTimeout_s);
    } catch (const std::exception& e) {  // refused, no answer, not sent, no rigid body: e says which
      *why = e.what();
      return false;
    }
    return true;
  }
  bool GetPayload(bridge::ArmPayloadMsg* payload, std::string*) override {
    *payload = arm_.payload();
    return true;
  }
  double Receive(double timeout_s) {
    arm_.ReadLatest(timeout_s, &state_);
    have_ = true;
    return state_.time;
  }
  std::string describe_clock() const {
    const nlohmann::json& c = arm_.describe().value("clock", nlohmann::json());
    return c.is_string() ? c.get<std::string>() : "";
  }
  double control_hz() const {
    const nlohmann::json& d = arm_.describe();
    return d.contains("rates") ? d["rates"].value("control_hz", 0.0) : 0.0;
  }

 private:
  bridge::Arm arm_;
  bridge::Arm::State state_;
  bool have_ = false;
  Eigen::VectorXd values_;
  std::vector<std::string> state_names_, command_names_;
};

class UdpWrench final : public Channel {
 public:
  explicit UdpWrench(bridge::Wrench w) : w_(std::move(w)) {}
  const std::string& name() const override { return w_.name(); }
  bridge::DeviceKind kind() const override { return bridge::DeviceKind::kWrench; }
  const std::vector<std::string>& state_names() const override { return names_; }
  const std::vector<std::string>& command_names() const override { return none_; }
  bool Read(std::vector<double>* v) override {
    if (!have_) return false;
    v->assign(state_.wrench.data(), state_.wrench.data() + 6);
    v->push_back(state_.filter);
    v->push_back(state_.saturated ? 1.0 : 0.0);
    return true;
  }
  bool Write(const std::vector<double>&, std::string* why) override {
    *why = "a wrench takes no commands";
    return false;
  }
  void Receive(double timeout_s) {
    state_ = w_.ReadLatest(timeout_s);
    have_ = true;
    if (++periods_ % 1000 == 0) w_.KeepAlive();
  }

 private:
  bridge::Wrench w_;
  bridge::Wrench::State state_;
  bool have_ = false;
  long periods_ = 0;
  std::vector<std::string> names_ = {"Fx", "Fy", "Fz", "Mx", "My", "Mz", "filter", "saturated"}, none_;
};

class UdpDevice final : public Channel {
 public:
  explicit UdpDevice(bridge::Device d) : d_(std::move(d)) {}
  const std::string& name() const override { return d_.name(); }
  bridge::DeviceKind kind() const override { return d_.kind(); }
  const std::vector<std::string>& state_names() const override { return d_.state_names(); }
  const std::vector<std::string>& command_names() const override { return d_.command_names(); }
  bool Read(std::vector<double>* v) override {
    if (!have_) return false;
    *v = state_.values;
    return true;
  }
  bool Write(const std::vector<double>& v, std::string* why) override {
    if (!d_.Write(v, state_.seq)) {
      *why = "the datagram could not be sent";
      return false;
    }
    return true;
  }
  void Receive(double timeout_s) {
    state_ = d_.ReadLatest(timeout_s);
    have_ = true;
    if (++periods_ % 1000 == 0) d_.KeepAlive();
  }

 private:
  bridge::Device d_;
  bridge::Device::State state_;
  bool have_ = false;
  long periods_ = 0;
};

}  // namespace

void SplitEndpoint(const std::string& endpoint, const std::string& what, std::string* host, int* port) {
  const auto colon = endpoint.rfind(':');
  int p = 0;
  try {
    p = colon == std::string::npos ? 0 : std::stoi(endpoint.substr(colon + 1));
  } catch (const std::exception&) {
    p = 0;
  }
  if (colon == std::string::npos || colon == 0 || p < 1 || p > 65535) {
    throw InputError(what + ": '" + endpoint + "' is not HOST:PORT (port 1..65535)");
  }
  *host = endpoint.substr(0, colon);
  *port = p;
}

struct UdpDevices::Impl {
  std::unique_ptr<UdpArm> arm;
  std::vector<std::unique_ptr<UdpWrench>> wrenches;
  std::vector<std::unique_ptr<UdpDevice>> others;
  std::map<std::string, Channel*> by_name;
  std::map<std::string, std::unique_ptr<UdpMarkers>> markers;
};

UdpDevices::UdpDevices() : impl_(std::make_unique<Impl>()) {}
UdpDevices::~UdpDevices() = default;

void UdpDevices::AddArm(const std::string& endpoint, double timeout_s) {
  std::string host;
  int port;
  SplitEndpoint(endpoint, "--arm", &host, &port);
  if (impl_->arm) throw InputError("--arm: one arm per vlab task (one robot program)");
  impl_->arm = std::make_unique<UdpArm>(bridge::Arm::Connect(host, port, timeout_s));
  impl_->by_name[impl_->arm->name()] = impl_->arm.get();
}

void UdpDevices::Add(const std::string& kind, const std::string& endpoint, double timeout_s) {
  std::string host;
  int port;
  SplitEndpoint(endpoint, "--" + kind, &host, &port);
  if (kind == "markers") {
    auto m = std::make_unique<UdpMarkers>("", endpoint, timeout_s);
    m->Open();
    if (impl_->by_name.count(m->name()) || impl_->markers.count(m->name())) {
      throw InputError("two devices named '" + m->name() + "'");
    }
    impl_->markers[m->name()] = std::move(m);
    return;
  }
  const bridge::KindLayout* layout = bridge::FindKindLayout(kind);
  if (!layout || !layout->float64) throw InputError("--device: '" + kind + "' is not a float64 device kind");
  Channel* c = nullptr;
  if (layout->kind == bridge::DeviceKind::kWrench) {
    impl_->wrenches.push_back(std::make_unique<UdpWrench>(bridge::Wrench::Connect(host, port, timeout_s)));
    c = impl_->wrenches.back().get();
  } else {
    impl_->others.push_back(std::make_unique<UdpDevice>(bridge::Device::Connect(layout->kind, host, port, timeout_s)));
    c = impl_->others.back().get();
  }
  if (impl_->by_name.count(c->name())) throw InputError("two devices named '" + c->name() + "'");
  impl_->by_name[c->name()] = c;
}

double UdpDevices::Receive(double timeout_s) {
  const double t = impl_->arm->Receive(timeout_s);
  for (auto& w : impl_->wrenches) w->Receive(timeout_s);
  for (auto& d : impl_->others) d->Receive(timeout_s);
  return t;
}

void UdpDevices::set_time_origin(double t_s) {
  for (auto& [name, m] : impl_->markers) m->set_time_origin(t_s);
}

bool UdpDevices::realtime() const { return impl_->arm && impl_->arm->describe_clock() == "realtime"; }

MarkerChannel* UdpDevices::FindMarkers(const std::string& name) {
  const auto it = impl_->markers.find(name);
  return it == impl_->markers.end() ? nullptr : it->second.get();
}

double UdpDevices::control_hz() const { return impl_->arm ? impl_->arm->control_hz() : 0.0; }
const std::string& UdpDevices::arm_name() const { return impl_->arm->name(); }

Channel* UdpDevices::Find(const std::string& name) {
  const auto it = impl_->by_name.find(name);
  return it == impl_->by_name.end() ? nullptr : it->second;
}

std::vector<std::string> UdpDevices::Names() const {
  std::vector<std::string> out;
  for (const auto& [name, c] : impl_->by_name) out.push_back(name);
  return out;
}

}  // namespace vlab::task
