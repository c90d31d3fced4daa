// vlab record NAME=HOST:PORT...: subscribes to devices over the wire (a real
// driver, vlab-kinsim, vlab serve, any server of the protocol) and writes the
// output folder a run writes: log.csv with the lab's column names and the
// devices' own stamps, summary.json with what was recorded and lost.
//
// Ports
//   input   every state of each device (one subscription each; never a
//           command), read on a thread per device; a describe request of
//           kind 0 first, whose reply names the device's kind
//   output  subscribe renewals (every kKeepAlive_s); the output folder,
//           staged and renamed into place at the end (lab_output.h)
// Rows, columns and counting: cli_record_table.h.
// Ends when every device has sent a state stamped --duration after the first
// state taken, or on SIGINT/SIGTERM; both write the folder (exit 0). Exit 2:
// a bad argument, a device that does not answer within --timeout, a kind
// that is not float64 (camera, markers); nothing is written then. Exit 1: a
// write failed (the staging folder is removed).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <fstream>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "bridge/bridge_client_device.h"
#include "bridge/bridge_layouts.h"
#include "bridge/bridge_program.h"
#include "bridge/bridge_session.h"
#include "bridge/bridge_signals.h"
#include "bridge/bridge_udp.h"
#include "cli/cli_commands.h"
#include "cli/cli_record_table.h"
#include "core/core_errors.h"
#include "lab/outputs/lab_log.h"
#include "lab/outputs/lab_output.h"

namespace vlab::cli::record {

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kKeepAlive_s = 1.0;  // a subscriber that never commands renews this often
constexpr double kRetry_s = 0.25;     // the kind's describe request is resent this often
// each device's socket buffer, where states wait while the recorder is not scheduled: the kernel
// grants twice what is asked, about 6,500 of a PA10's states (1.3 kB each as it counts them),
// 13 s at 500 Hz; its default 208 KiB held 167 (0.33 s), and a recorder stalled longer than
// that on a busy machine lost the states that came next
constexpr int kReceiveBufferBytes = 4 << 20;

struct RecordArgs {
  std::vector<std::string> devices;  // NAME=HOST:PORT
  std::string out_dir;
  double duration_s = -1;  // of stamps; < 0: not given (until a signal)
  double timeout_s = 5;
  bool quiet = false;
};

// one device to record: its argument, then what connecting learnt
struct Source {
  std::string name, text;
  bridge::program::Address address;
  std::string kind;
  std::unique_ptr<bridge::Device> device;
  std::vector<std::string> columns;
  int receive_buffer = -1;  // bytes the kernel granted
  std::atomic<long> malformed{0};
};

// a state a reader thread took
struct Taken {
  int device = 0;
  bridge::Device::State state;
};

std::string Num(double x) {
  char s[32];
  std::snprintf(s, sizeof s, "%g", x);
  return s;
}

double Seconds(Clock::time_point since) { return std::chrono::duration<double>(Clock::now() - since).count(); }

// NAME=HOST:PORT, or exit 2 naming the argument
void ParseSource(const std::string& text, Source* s) {
  const std::size_t eq = text.find('=');
  s->text = text;
  if (eq == std::string::npos || eq == 0 || !bridge::program::ParseAddress(text.substr(eq + 1), &s->address)) {
    throw InputError("record: '" + text + "': expected NAME=HOST:PORT (e.g. pa10=127.0.0.1:50010)");
  }
  s->name = text.substr(0, eq);
  const bool ok = std::all_of(s->name.begin(), s->name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
  });
  if (!ok) throw InputError("record: '" + text + "': NAME may hold only letters, digits, '_' and '-'");
}

// the kind a device's describe reply names: a describe request of kind 0 (any), its cookie, then
// the request again with it; throws InputError naming the source when nothing answers
std::string DiscoverKind(const Source& s, double timeout_s) {
  const bridge::Endpoint device = bridge::UdpSocket::Resolve(s.address.host, s.address.port);
  std::unique_ptr<bridge::UdpSocket> socket = bridge::UdpSocket::Bind(device.address().is_v6() ? "::" : "0.0.0.0", 0);
  std::vector<unsigned char> request, buffer(bridge::kDatagramBufferBytes);
  bridge::Header header;
  std::vector<double> payload;
  double cookie = 0;
  const Clock::time_point start = Clock::now();
  Clock::time_point resend = start;
  while (Seconds(start) < timeout_s && !StopRequested()) {
    if (Clock::now() >= resend) {
      bridge::EncodeDescribeRequest(0, cookie, &request);
      socket->SendTo(request.data(), request.size(), device);
      resend = Clock::now() + std::chrono::milliseconds(static_cast<int>(kRetry_s * 1000));
    }
    bridge::Endpoint from;
    const long n = socket->Receive(buffer.data(), buffer.size(), &from, std::min(kRetry_s, bridge::program::kPoll_s));
    if (n <= 0 || from.port() != device.port()) continue;
    if (buffer[0] == '{') {
      nlohmann::json reply = nlohmann::json::parse(buffer.begin(), buffer.begin() + n, nullptr, false);
      const nlohmann::json kind = reply.is_object() ? reply.value("kind", nlohmann::json()) : nlohmann::json();
      if (!kind.is_string()) throw InputError("record: " + s.text + ": the describe reply names no kind");
      return kind.get<std::string>();
    }
    bridge::SessionResult result{};
    if (bridge::DecodePacket(buffer.data(), static_cast<std::size_t>(n), &header, &payload) ==
            bridge::DecodeError::kNone &&
        bridge::ParseSessionReply(header, payload, &cookie, &result) && result == bridge::SessionResult::kChallenge) {
      resend = Clock::now();  // ask again at once, with the cookie
    }
  }
  throw InputError("record: " + s.text + ": no device answered within " + Num(timeout_s) +
                   " s (is a server of protocol version " + std::to_string(bridge::kProtocolVersion) +
                   " on that address and port?)");
}

// describes and subscribes to one source; exit 2 naming it on any failure
void Connect(Source* s, double timeout_s) {
  try {
    s->kind = DiscoverKind(*s, timeout_s);
  } catch (const bridge::BridgeError& e) {  // an address that does not resolve, no socket
    throw InputError("record: " + s->text + ": " + e.what());
  }
  const bridge::KindLayout* layout = bridge::FindKindLayout(s->kind);
  if (layout == nullptr) throw InputError("record: " + s->text + ": unknown device kind '" + s->kind + "'");
  if (!layout->float64) {
    throw InputError("record: " + s->text + ": a " + s->kind + " device sends no float64 states (" + layout->note +
                     "); vlab record records the others");
  }
  try {
    s->device = std::make_unique<bridge::Device>(
        bridge::Device::Connect(layout->kind, s->address.host, s->address.port, timeout_s));
    s->columns = StateColumns(s->name, s->kind, s->device->state_names(), s->device->describe());
    s->receive_buffer = s->device->GrowReceiveBuffer(kReceiveBufferBytes);
  } catch (const std::exception& e) {  // a bridge error, or an arm whose joints do not fit its layout
    throw InputError("record: " + s->text + ": " + e.what());
  }
}

// reads one device's states into the queue until `stop`, renewing its subscription
void ReadDevice(int index, Source* s, const std::atomic<bool>* stop, std::mutex* mutex, std::condition_variable* cv,
                std::deque<Taken>* queue) {
  Clock::time_point renewed = Clock::now();
  while (!stop->load()) {
    try {
      Taken t{index, s->device->Read(bridge::program::kPoll_s)};
      {
        const std::lock_guard<std::mutex> lock(*mutex);
        queue->push_back(std::move(t));
      }
      cv->notify_one();
    } catch (const bridge::TimeoutError&) {
    } catch (const bridge::ProtocolError&) {
      ++s->malformed;  // a datagram that is no state of this device: counted, skipped
    } catch (const std::exception&) {
      ++s->malformed;  // (a network error on a datagram: counted too, and the reading goes on)
    }
    if (Seconds(renewed) >= kKeepAlive_s) {
      s->device->KeepAlive();
      renewed = Clock::now();
    }
  }
}

// a describe reply's text field, or "" (a reply is the device's: any JSON)
std::string Text(const nlohmann::json& reply, const char* field) {
  const auto it = reply.find(field);
  return it != reply.end() && it->is_string() ? it->get<std::string>() : std::string();
}

// the reader threads of the devices and the queue they fill; stops and joins them when destroyed
class Readers {
 public:
  ~Readers() { Stop(); }
  // starts reading device `index`
  void Start(int index, Source* source) {
    threads_.emplace_back(ReadDevice, index, source, &stop_, &mutex_, &cv_, &queue_);
  }
  // moves the queued states to *out, waiting up to wait_s for the first
  void Take(std::deque<Taken>* out, double wait_s) {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait_for(lock, std::chrono::duration<double>(wait_s), [this] { return !queue_.empty(); });
    for (Taken& t : queue_) out->push_back(std::move(t));
    queue_.clear();
  }
  void Stop() {
    stop_ = true;
    for (std::thread& t : threads_) t.join();
    threads_.clear();
  }

 private:
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Taken> queue_;
  std::vector<std::thread> threads_;
};

nlohmann::ordered_json Stamp(double t) { return std::isfinite(t) ? nlohmann::ordered_json(t) : nullptr; }

nlohmann::ordered_json Summary(const RecordArgs& a, const std::vector<std::unique_ptr<Source>>& sources,
                               const RecordTable& table, int signal) {
  nlohmann::ordered_json j;
  j["command"] = "record";
  j["vlab_version"] = VLAB_VERSION;
  j["result"] = signal != 0 ? "interrupted" : "duration";
  if (signal != 0) j["signal"] = signal == SIGINT ? "SIGINT" : "SIGTERM";
  j["duration_s"] = a.duration_s > 0 ? nlohmann::ordered_json(a.duration_s) : nullptr;
  j["rows"] = table.rows();
  j["first_stamp"] = Stamp(table.first_stamp());
  j["last_stamp"] = Stamp(table.last_stamp());
  j["devices"] = nlohmann::ordered_json::array();
  for (std::size_t i = 0; i < sources.size(); ++i) {
    const Source& s = *sources[i];
    const DeviceCounts& c = table.counts(static_cast<int>(i));
    const nlohmann::json& d = s.device->describe();
    nlohmann::ordered_json e;
    e["name"] = s.name;
    e["kind"] = s.kind;
    e["device_name"] = s.device->name();
    e["address"] = s.address.host;
    e["port"] = s.address.port;
    e["server"] = Text(d, "server");
    e["clock"] = Text(d, "clock");
    e["columns"] = s.columns;
    e["receive_buffer_bytes"] = s.receive_buffer;
    e["states"] = c.states;
    e["lost"] = c.lost;
    e["refused"] = c.refused;
    e["late"] = c.late;
    e["malformed"] = s.malformed.load();
    e["first_seq"] = c.first_seq >= 0 ? nlohmann::ordered_json(c.first_seq) : nullptr;
    e["last_seq"] = c.last_seq >= 0 ? nlohmann::ordered_json(c.last_seq) : nullptr;
    e["first_stamp"] = Stamp(c.first_stamp);
    e["last_stamp"] = Stamp(c.last_stamp);
    j["devices"].push_back(std::move(e));
  }
  return j;
}

int Record(const RecordArgs& a) {
  InstallStopSignals();
  if (a.devices.empty()) throw InputError("record: no device given (NAME=HOST:PORT ...)");
  if (!(a.timeout_s > 0) || !std::isfinite(a.timeout_s)) throw InputError("record: --timeout must be > 0 s");
  if (a.duration_s != -1 && !(a.duration_s > 0 && a.duration_s <= 1e6)) {
    throw InputError("record: --duration must be > 0 s and at most 1e6 s");
  }
  // every argument is checked before anything is sent
  std::vector<std::unique_ptr<Source>> sources;
  for (const std::string& text : a.devices) {
    auto s = std::make_unique<Source>();
    ParseSource(text, s.get());
    for (const auto& other : sources) {
      if (other->name == s->name) throw InputError("record: '" + text + "': the name '" + s->name + "' is given twice");
    }
    sources.push_back(std::move(s));
  }
  // each device's reader starts once it is subscribed, so that its states wait in the queue,
  // not in its socket's buffer, while the next ones connect
  Readers readers;
  for (std::size_t i = 0; i < sources.size(); ++i) {
    Connect(sources[i].get(), a.timeout_s);
    if (StopRequested()) return 0;  // stopped before recording: nothing to write
    readers.Start(static_cast<int>(i), sources[i].get());
  }
  std::string out_dir = a.out_dir;
  if (out_dir.empty()) {
    out_dir = "out/record";
    for (const auto& s : sources) out_dir += "-" + s->name;
  }
  std::unique_ptr<lab::OutputDir> out = lab::OutputDir::Create(out_dir);
  std::vector<std::string> columns = {"time"};
  std::vector<int> widths;
  for (const auto& s : sources) {
    columns.insert(columns.end(), s->columns.begin(), s->columns.end());
    widths.push_back(static_cast<int>(s->columns.size()));
  }
  std::unique_ptr<lab::RunLog> log = lab::RunLog::Open(out->File("log.csv"), columns);
  RecordTable table(widths, std::max(a.duration_s, 0.0));

  // the start line: every device is subscribed now, so no state it sends from here is missed
  std::string line = "vlab record:";
  for (const auto& s : sources) {
    line += " " + s->name + " (" + s->kind + ") " + s->address.host + ":" + std::to_string(s->address.port) + ";";
  }
  std::printf("%s writing %s\n", line.c_str(), out_dir.c_str());
  std::fflush(stdout);

  std::deque<Taken> taken;
  const auto append = [&log](const double* row) { log->Append(row); };
  const auto take = [&] {
    for (const Taken& t : taken) table.Add(t.device, t.state.seq, t.state.time, t.state.values.data());
    taken.clear();
  };
  while (!table.Done() && !StopRequested() && !log->failed()) {
    readers.Take(&taken, 0.05);
    take();
    table.Drain(false, append);
  }
  readers.Stop();
  readers.Take(&taken, 0);  // what came before the readers stopped
  take();
  table.Drain(true, append);
  log->Close();  // throws on a write error: the staging folder goes with `out`
  const int signal = static_cast<int>(g_stop_requested);
  {
    std::ofstream file(out->File("summary.json"));
    file << Summary(a, sources, table, table.Done() ? 0 : signal).dump(2) << "\n";
    if (!file.flush()) throw std::runtime_error(out->File("summary.json") + ": write failed");
  }
  const std::string where = out->Commit();
  if (!out->note().empty()) std::fprintf(stderr, "vlab record: %s\n", out->note().c_str());
  if (!a.quiet) {
    for (std::size_t i = 0; i < sources.size(); ++i) {
      const DeviceCounts& c = table.counts(static_cast<int>(i));
      std::printf("  %-8s states %ld, lost %ld, refused %ld, late %ld, malformed %ld\n", sources[i]->name.c_str(),
                  c.states, c.lost, c.refused, c.late, sources[i]->malformed.load());
    }
  }
  std::printf("vlab record: %ld rows, t = %s .. %s s; output in %s/\n", table.rows(), Num(table.first_stamp()).c_str(),
              Num(table.last_stamp()).c_str(), where.c_str());
  return 0;
}

}  // namespace

}  // namespace vlab::cli::record

namespace vlab::cli {

Subcommand AddRecordCommand(CLI::App& app) {
  auto args = std::make_shared<record::RecordArgs>();
  CLI::App* cmd = app.add_subcommand(
      "record",
      "Record devices over the wire (a real driver, vlab-kinsim, vlab serve) into the output folder a run writes: "
      "log.csv (time, then each device's values under the lab's column names, one row per stamp the devices "
      "sent) and summary.json (devices, states, lost and refused ones). Ends after --duration of stamps or on "
      "SIGINT/SIGTERM (exit 0); exit 2 on a bad argument or a device that does not answer (nothing written)");
  cmd->add_option("DEVICE", args->devices,
                  "NAME=HOST:PORT: a device to record; NAME prefixes its columns (pa10 gives pa10.q.S1)")
      ->required();
  cmd->add_option("--out", args->out_dir,
                  "Output folder (default out/record-NAME[-NAME...]); replaced only as vlab run's");
  cmd->add_option("--duration", args->duration_s,
                  "End once every device has sent a state stamped this long after the first state taken, s of the "
                  "devices' stamps (default: until SIGINT/SIGTERM)");
  cmd->add_option("--timeout", args->timeout_s, "Each device must answer within this long, s (default 5)");
  cmd->add_flag("-q,--quiet", args->quiet, "No per-device counter lines at the end");
  return {cmd, [args] { return WithErrorReport([&] { return record::Record(*args); }); }};
}

}  // namespace vlab::cli
