// The camera stream over real loopback sockets: CameraServer -> CameraClient.
//   - 640x480 at 30 Hz for 10 s, raw and JPEG side by side: all 300 frames of
//     each arrive, in order, and every byte is the byte sent (no frame lost,
//     none torn);
//   - chunk loss injected at the server (seeded): exactly the damaged frames
//     are dropped, the others (later ones included) arrive whole.
// The client asks for an 8 MiB receive buffer (SO_RCVBUF, then SO_RCVBUFFORCE
// where permitted): a raw frame is 16 datagrams of 60 kB sent back to back.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "bridge/bridge_camera_client.h"
#include "bridge/bridge_camera_server.h"
#include "camera_test_util.h"
#include "render/image_codec.h"

namespace vlab::bridge {
namespace {

using Clock = std::chrono::steady_clock;
using testing::FillPattern;
using testing::FirstPatternMismatch;

constexpr int kW = 640, kH = 480, kFrames = 300;
constexpr double kFps = 30;
constexpr int kJpegQuality = 90;

// a smooth picture that changes with the frame (JPEG keeps it close)
void FillSmooth(std::int64_t id, std::vector<std::uint8_t>* rgb) {
  auto tri = [](long v) { return static_cast<std::uint8_t>(v % 512 < 256 ? v % 512 : 511 - v % 512); };
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      std::uint8_t* p = rgb->data() + 3 * (static_cast<std::size_t>(y) * kW + x);
      p[0] = tri(x + 4 * id);
      p[1] = tri(2 * y + 8 * id);
      p[2] = tri(x + y + 2 * id);
    }
  }
}

std::vector<std::uint8_t> EncodeJpeg(const std::vector<std::uint8_t>& rgb) {
  std::vector<std::uint8_t> out;
  render::EncodeJpeg({kW, kH, 3, 8, rgb.data(), 0}, kJpegQuality, &out);
  return out;
}

std::unique_ptr<CameraServer> MakeServer(CameraEncoding encoding, int w, int h, double drop = 0) {
  CameraServerConfig config;
  config.description.name = encoding == CameraEncoding::kRaw ? "raw" : "jpeg";
  config.description.server = "camera_stream_test";
  config.description.width = w;
  config.description.height = h;
  config.description.fps = kFps;
  config.description.encoding = encoding;
  config.description.jpeg_quality = kJpegQuality;
  config.description.fx = config.description.fy = 500;
  config.test_drop_probability = drop;
  config.test_drop_seed = 3;
  return CameraServer::Create(config);
}

bool WaitSubscribed(CameraServer& server) {
  const Clock::time_point give_up = Clock::now() + std::chrono::seconds(10);
  while (server.subscribers() == 0 && Clock::now() < give_up) server.Poll(0.05);
  return server.subscribers() > 0;
}

// sends kFrames frames paced at kFps, answering requests in between
void Serve(CameraServer* server, bool smooth, std::atomic<long>* sent) {
  if (!WaitSubscribed(*server)) return;
  std::vector<std::uint8_t> rgb(3u * kW * kH);
  const Clock::time_point start = Clock::now();
  for (int i = 0; i < kFrames; ++i) {
    const Clock::time_point due = start + std::chrono::microseconds(static_cast<long>(i * 1e6 / kFps));
    while (Clock::now() < due) server->Poll(std::chrono::duration<double>(due - Clock::now()).count());
    smooth ? FillSmooth(i, &rgb) : FillPattern(i, &rgb);
    const double t = std::chrono::duration<double>(Clock::now() - start).count();
    if (server->SendImage(i, t, rgb.data(), CameraPose())) ++*sent;
  }
}

struct Received {
  long frames = 0, lost = 0, torn = 0, wrong_size = 0;
  double worst_jpeg_error = 0, mean_jpeg_error = 0;
  std::size_t jpeg_bytes = 0;
  std::string first_problem;
  long dropped = 0, refused = 0;
  int receive_buffer = 0;
};

void Receive(int port, bool jpeg, Received* r) {
  CameraClient client = CameraClient::Connect("127.0.0.1", port);
  r->receive_buffer = client.receive_buffer_bytes();
  CameraClient::Frame f;
  std::vector<std::uint8_t> expected(3u * kW * kH);
  double error_sum = 0;
  for (std::int64_t want = 0; want < kFrames;) {
    try {
      client.Receive(3.0, &f);
    } catch (const TimeoutError& e) {
      r->first_problem = r->first_problem.empty() ? e.what() : r->first_problem;
      break;
    }
    if (f.id != want) {
      ++r->lost;
      if (r->first_problem.empty()) r->first_problem = "frame " + std::to_string(want) + " lost";
      want = f.id;
    }
    ++want;
    ++r->frames;
    if (f.width != kW || f.height != kH || f.rgb.size() != expected.size()) {
      ++r->wrong_size;
      continue;
    }
    if (!jpeg) {
      // every byte as sent
      if (FirstPatternMismatch(f.id, f.data) != -1 || f.rgb != f.data) ++r->torn;
      continue;
    }
    // the JPEG file byte for byte as the server encoded it, and its picture close to the original
    FillSmooth(f.id, &expected);
    const std::vector<std::uint8_t> file = EncodeJpeg(expected);
    if (f.encoding != CameraEncoding::kJpeg || f.data.size() != file.size() ||
        !std::equal(file.begin(), file.end(), f.data.begin())) {
      ++r->torn;
      continue;
    }
    r->jpeg_bytes = std::max(r->jpeg_bytes, file.size());
    double sum = 0;
    for (std::size_t i = 0; i < expected.size(); ++i) {
      const double e = std::abs(static_cast<double>(f.rgb[i]) - expected[i]);
      sum += e;
      r->worst_jpeg_error = std::max(r->worst_jpeg_error, e);
    }
    error_sum += sum / static_cast<double>(expected.size());
  }
  r->mean_jpeg_error = r->frames > 0 ? error_sum / static_cast<double>(r->frames) : 0;
  r->dropped = client.counters().frames_dropped;
  r->refused = client.counters().refused;
}

TEST(CameraStreamTest, Vga30HzFor10sRawAndJpegNoFrameLostOrTorn) {
  auto raw_server = MakeServer(CameraEncoding::kRaw, kW, kH);
  auto jpeg_server = MakeServer(CameraEncoding::kJpeg, kW, kH);
  std::atomic<long> raw_sent{0}, jpeg_sent{0};
  Received raw, jpeg;
  const Clock::time_point start = Clock::now();
  std::thread raw_client(Receive, raw_server->port(), false, &raw);
  std::thread jpeg_client(Receive, jpeg_server->port(), true, &jpeg);
  std::thread raw_thread(Serve, raw_server.get(), false, &raw_sent);
  std::thread jpeg_thread(Serve, jpeg_server.get(), true, &jpeg_sent);
  raw_thread.join();
  jpeg_thread.join();
  raw_client.join();
  jpeg_client.join();
  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();

  std::printf("10 s at 30 Hz, 640x480 over loopback (%.2f s), client SO_RCVBUF %d bytes:\n", elapsed,
              raw.receive_buffer);
  std::printf(
      "  raw:  %ld/%d frames whole, %ld lost, %ld torn, %ld dropped incomplete, %ld chunks sent, "
      "%ld send failures\n",
      raw.frames, kFrames, raw.lost, raw.torn, raw.dropped, raw_server->counters().chunks_sent,
      raw_server->counters().send_failures);
  std::printf(
      "  jpeg: %ld/%d frames whole, %ld lost, %ld torn, %ld dropped incomplete; up to %zu bytes a frame; "
      "decoded vs original: mean |error| %.2f, worst %.0f grey levels\n",
      jpeg.frames, kFrames, jpeg.lost, jpeg.torn, jpeg.dropped, jpeg.jpeg_bytes, jpeg.mean_jpeg_error,
      jpeg.worst_jpeg_error);
  for (const Received* r : {&raw, &jpeg}) {
    EXPECT_EQ(r->frames, kFrames) << r->first_problem;
    EXPECT_EQ(r->lost, 0) << r->first_problem;
    EXPECT_EQ(r->torn, 0);
    EXPECT_EQ(r->wrong_size, 0);
    EXPECT_EQ(r->dropped, 0);
    EXPECT_EQ(r->refused, 0);
  }
  EXPECT_EQ(raw_sent.load(), kFrames);
  EXPECT_EQ(jpeg_sent.load(), kFrames);
  EXPECT_EQ(raw_server->counters().chunks_sent, 16L * kFrames);  // 921600 bytes in chunks of 60000
  EXPECT_EQ(raw_server->counters().send_failures, 0);
  EXPECT_LT(jpeg.mean_jpeg_error, 2.0);
  EXPECT_GT(raw.receive_buffer, 2 * 1024 * 1024) << "a small receive buffer risks loss under load";
}

TEST(CameraStreamTest, InjectedChunkLossDropsExactlyTheDamagedFrames) {
  constexpr int w = 160, h = 120, frames = 100;  // 57600 bytes: 15 chunks of 4000
  CameraServerConfig config;
  config.description.width = w;
  config.description.height = h;
  config.description.encoding = CameraEncoding::kRaw;
  config.description.fx = config.description.fy = 100;
  config.chunk_bytes = 4000;
  config.test_drop_probability = 0.02;
  config.test_drop_seed = 11;
  auto server = CameraServer::Create(config);
  std::set<std::int64_t> whole, received;
  std::thread sender([&] {
    if (!WaitSubscribed(*server)) return;
    std::vector<std::uint8_t> rgb(3u * w * h);
    for (int i = 0; i < frames; ++i) {
      const long damaged_before = server->counters().test_damaged_frames;
      FillPattern(i, &rgb);
      server->SendImage(i, i / kFps, rgb.data(), CameraPose());
      if (server->counters().test_damaged_frames == damaged_before) whole.insert(i);
      server->Poll(0.002);
    }
  });
  CameraClientOptions options;
  options.assembler.timeout_s = 0.3;
  CameraClient client = CameraClient::Connect("127.0.0.1", server->port(), options);
  CameraClient::Frame f;
  long torn = 0;
  for (;;) {
    try {
      client.Receive(1.0, &f);
    } catch (const TimeoutError&) {
      break;
    }
    received.insert(f.id);
    if (FirstPatternMismatch(f.id, f.data) != -1) ++torn;
  }
  sender.join();
  const long damaged = frames - static_cast<long>(whole.size());
  std::printf(
      "loss: %ld chunks dropped at the server, %ld of %d frames damaged; client: %zu frames whole, "
      "%ld dropped incomplete (%ld superseded, %ld timed out), %ld torn\n",
      server->counters().test_dropped_chunks, damaged, frames, received.size(), client.counters().frames_dropped,
      client.counters().dropped_superseded, client.counters().dropped_timeout, torn);
  EXPECT_EQ(torn, 0);
  EXPECT_EQ(received, whole) << "exactly the frames sent whole arrive";
  ASSERT_GT(damaged, 5) << "the hook must damage some frames for this test to mean anything";
  EXPECT_LT(damaged, 60);
  EXPECT_EQ(client.counters().frames_dropped, damaged);
  // later frames still arrive: some whole frame after the first damaged one
  std::int64_t first_damaged = 0;
  while (whole.count(first_damaged)) ++first_damaged;
  EXPECT_GT(*whole.rbegin(), first_damaged);
}

}  // namespace
}  // namespace vlab::bridge
