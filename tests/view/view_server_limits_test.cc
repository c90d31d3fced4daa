// Tests that no client of the view's server (src/view/view_server*.cc) can
// lock another out, with the attacker on the viewer's own address
// (127.0.0.1, as on a single-user machine):
//   - 200 slow connections (a request head never finished) and 16 WebSockets
//     that never read, all held open, while a normal client loads the page
//     and receives pose frames; the server's memory stays flat;
//   - slow connections are closed at the header deadline, WebSockets that do
//     not read when they answer no ping, while a reading one stays;
//   - the tables: a full WebSocket table closes a new session with code 1013
//     and "server full"; one address cannot take another's places; when the
//     HTTP table is full the connection waiting longest for a request makes
//     room.
// No bound here is on wall time: each wait has a generous limit that turns a
// hang into a failure, and the time the viewer took is printed.
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <future>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "view/view_server.h"
#include "view_clients.h"

namespace vlab::view {
namespace {

using namespace view_test;  // NOLINT: the clients of view_clients.h

// the resident memory of this process (server and clients), KiB
long RssKiB() {
  std::ifstream status("/proc/self/status");
  std::string key;
  long value = 0;
  while (status >> key) {
    if (key == "VmRSS:") {
      status >> value;
      return value;
    }
    status.ignore(1 << 16, '\n');
  }
  return -1;
}

// a connection that sends a request head's first bytes and never the rest
int SlowConnection(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (fd < 0 || ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0) return -1;
  const std::string start = "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: ";
  if (::send(fd, start.data(), start.size(), MSG_NOSIGNAL) < 0) return -1;
  return fd;
}

// true once the server has closed fd (EOF or reset), within limit_s
bool ClosedWithin(int fd, double limit_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(limit_s);
  char buffer[4096];
  while (std::chrono::steady_clock::now() < end) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 50) <= 0) continue;
    if (::recv(fd, buffer, sizeof(buffer), 0) <= 0) return true;  // data (pings, frames) read at the TCP level only
  }
  return false;
}

// a publisher of pose-sized frames (a PA10 scene: 16 + 28 x 12 bytes) at about 100 Hz until stopped
class Publisher {
 public:
  explicit Publisher(ViewServer* server)
      : thread_([this, server] {
          for (long i = 0; !stop_; ++i) {
            server->Publish(std::string(352, static_cast<char>('a' + i % 26)));
            std::this_thread::sleep_for(std::chrono::milliseconds(10));  // pacing, not synchronisation
          }
        }) {}
  ~Publisher() {
    stop_ = true;
    thread_.join();
  }

 private:
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

constexpr int kSlow = 200, kSilent = 16, kFrames = 30;  // the attack to withstand; 1 s of poses at 30 Hz
constexpr double kHangLimit_s = 20;                     // a guard against a hang, not a bound

// polls `done` until it holds or kHangLimit_s pass; whether it held
template <typename Done>
bool WaitUntil(Done done) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(kHangLimit_s);
  while (!done()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));  // polling a condition, with a limit
  }
  return true;
}

// a normal viewer: the page, then kFrames pose frames; the seconds it took
double LoadPageAndFrames(int port) {
  const auto start = std::chrono::steady_clock::now();
  const std::string page = Get(port, "/");
  EXPECT_EQ(Status(page), 200) << page.substr(0, 80);
  EXPECT_NE(page.find(kPage), std::string::npos);
  WsClient viewer(port, "/ws", "http://127.0.0.1:" + std::to_string(port));
  EXPECT_EQ(viewer.Read().size(), 352u);
  const double first_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (int i = 1; i < kFrames; ++i) EXPECT_EQ(viewer.Read().size(), 352u);
  std::printf("the page and the first frame in %.3f s; ", first_s);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

TEST(ViewServerLimitsTest, SlowConnectionsAndSilentWebSocketsDoNotLockOutAViewer) {
  auto server = StartServer(ViewServerConfig());  // the defaults of vlab view
  const int port = server->port();
  Publisher publisher(server.get());
  LoadPageAndFrames(port);  // warm: buffers, the first session
  const long rss_before = RssKiB();
  for (int round = 0; round < 3; ++round) {
    std::vector<int> slow;
    for (int i = 0; i < kSlow; ++i) slow.push_back(SlowConnection(port));
    std::vector<std::unique_ptr<WsClient>> silent;  // handshake, then never read
    for (int i = 0; i < kSilent; ++i) silent.push_back(std::make_unique<WsClient>(port));
    EXPECT_TRUE(WaitUntil([&] { return server->clients() == kSilent; })) << "round " << round;
    const double took_s = LoadPageAndFrames(port);
    EXPECT_GE(server->clients(), kSilent) << "round " << round << ": still held when the viewer was done";
    std::printf(
        "round %d: %d slow connections (%d held by the server) and %d silent WebSockets: the viewer had "
        "%d frames in %.3f s\n",
        round, kSlow, server->http_connections(), kSilent, kFrames, took_s);
    for (const int fd : slow) {
      EXPECT_GE(fd, 0);
      ::close(fd);
    }
    silent.clear();
    EXPECT_TRUE(WaitUntil([&] { return server->clients() == 0; })) << "round " << round;
  }
  // flat: the server holds at most 32 HTTP connections and 16 + 1 sessions from one address, whatever is
  // sent; measured +0.3 MiB (server and clients) over the three rounds; 4 MiB is that times about 10
  const long grown_KiB = RssKiB() - rss_before;
  std::printf("RSS %ld KiB before the attack, %+ld KiB after three rounds\n", rss_before, grown_KiB);
  EXPECT_LT(grown_KiB, 4 * 1024);
  const ViewServerCounters c = server->counters();
  EXPECT_GE(c.evicted, 3 * (kSlow - 32)) << "the slow connections beyond one address's 32 made room";
  EXPECT_EQ(c.refused, 0);
}

TEST(ViewServerLimitsTest, SlowConnectionsAndSilentWebSocketsAreClosed) {
  ViewServerConfig config;
  config.header_timeout_s = 1;  // short, for a short test; vlab view's are 5 and 10 s
  config.ws_idle_timeout_s = 2;
  auto server = StartServer(config);
  const int port = server->port();
  std::vector<int> slow;
  for (int i = 0; i < 5; ++i) slow.push_back(SlowConnection(port));
  WsClient silent_a(port), silent_b(port), reader(port);
  // reading until "end", it answers the pings: the first message it gets, or why none came
  std::promise<std::string> first;
  std::thread reading([&] {
    try {
      first.set_value(reader.Read());
      while (reader.Read() != "end") {
      }
    } catch (const std::exception& e) {
      try {
        first.set_value(e.what());
      } catch (const std::future_error&) {  // (after the first)
      }
    }
  });
  for (const int fd : slow) {
    EXPECT_TRUE(ClosedWithin(fd, kHangLimit_s)) << "a slow connection outlives the header deadline";
    ::close(fd);
  }
  // the silent ones read only at the TCP level: the pings come, no pong goes back
  EXPECT_TRUE(ClosedWithin(silent_a.native_handle(), kHangLimit_s));
  EXPECT_TRUE(ClosedWithin(silent_b.native_handle(), kHangLimit_s));
  // the reader has stayed as long as they took to be closed
  server->Publish("after");
  EXPECT_EQ(first.get_future().get(), "after");
  // counted as the sessions end (their handlers may run just after the client sees the close);
  // a silent one is counted slow whether its read or the write of "after" met the timeout
  EXPECT_TRUE(WaitUntil([&] { return server->counters().header_timeouts == 5; })) << server->counters().header_timeouts;
  EXPECT_TRUE(WaitUntil([&] { return server->counters().ws_closed_slow == 2; })) << server->counters().ws_closed_slow;
  EXPECT_TRUE(WaitUntil([&] { return server->clients() == 1; })) << "the reader alone";
  server->Publish("end");
  reading.join();
}

TEST(ViewServerLimitsTest, TablesAreBoundedPerServerAndPerAddress) {
  ViewServerConfig config;
  config.max_connections = 4;
  config.max_per_address = 2;
  auto server = StartServer(config);
  const int port = server->port();
  server->Publish("pose");
  auto refusal = [](WsClient& c) {
    std::string reason;
    try {
      c.Read();
    } catch (const WsError&) {
      reason = c.close_reason().reason;
      EXPECT_EQ(c.close_reason().code, kCloseTryAgainLater);
    }
    return reason;
  };
  // two from 127.0.0.1 fill its places; a third is told why; 127.0.0.2 still has its own
  WsClient a(port), b(port);
  EXPECT_EQ(a.Read(), "pose");
  EXPECT_EQ(b.Read(), "pose");
  WsClient c(port);
  EXPECT_NE(refusal(c).find("server full: 2 sessions from 127.0.0.1"), std::string::npos);
  WsClient d(port, "/ws", "", "127.0.0.2"), e(port, "/ws", "", "127.0.0.2");
  EXPECT_EQ(d.Read(), "pose");
  EXPECT_EQ(e.Read(), "pose");
  // four in all: the table is full for anyone
  WsClient f(port, "/ws", "", "127.0.0.3");
  EXPECT_NE(refusal(f).find("server full: 4 sessions open"), std::string::npos);
  EXPECT_EQ(server->counters().refused, 2);

  // HTTP: two idle connections from 127.0.0.1; a third connection from there closes the one waiting longest
  Raw idle_1(port), idle_2(port), other(port, "127.0.0.2");
  ASSERT_TRUE(WaitUntil([&] { return server->http_connections() == 3; }));
  EXPECT_EQ(Status(Get(port, "/")), 200);
  idle_1.ReadAll(kHangLimit_s);
  EXPECT_TRUE(idle_1.closed()) << "the oldest idle connection from 127.0.0.1 made room";
  // 127.0.0.2's idle connection was not touched: it is served
  EXPECT_EQ(Status(other.Send("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n").ReadAll()), 200);
  EXPECT_EQ(Status(idle_2.Send("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n").ReadAll()), 200);
  EXPECT_EQ(server->counters().evicted, 1);
}

}  // namespace
}  // namespace vlab::view
