// The webcam's render worker (src/lab/devices/device_camera.h, "Threading"),
// driven period by period as the lab drives it: a served camera renders and
// encodes on its own thread from a copy of the state at the frame's stamp.
// - lockstep: the frame of stamp s goes out in the period whose end is the first
//   at or after s + latency, with exactly the pixels a renderer on the test's
//   thread draws of that state, whether or not two threads compete for the CPU;
// - injected faults: a dropped frame is never sent, a late one is held its
//   late_by and the frames due behind it go out with it, in order;
// - realtime: every frame goes out, in order, with the same pixels; the control
//   thread never waits for the worker, and a frame sent after its period is
//   counted late (checked against what the test saw after each period).
#include <sched.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <functional>
#include <future>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "bridge/bridge_camera_client.h"
#include "core/core_mujoco.h"
#include "core/core_realtime.h"
#include "lab/devices/device_camera.h"
#include "render/renderer.h"

namespace vlab::lab::camera_worker_test {
namespace {

// a ball falling past a camera that looks at it from the side: every frame differs
constexpr const char* kSceneXml = R"(
<mujoco>
  <visual><global offwidth="640" offheight="480"/></visual>
  <worldbody>
    <light pos="0 -2 3" dir="0 0.5 -1"/>
    <geom type="plane" size="2 2 0.1" rgba="0.8 0.8 0.8 1"/>
    <body name="ball" pos="0 0 1.2"><freejoint/><geom type="sphere" size="0.05" rgba="1 0 0 1"/></body>
    <camera name="side" pos="0 -1.5 0.7" xyaxes="1 0 0 0 0 1" fovy="60"/>
  </worldbody>
</mujoco>)";

constexpr double kPeriod = 0.002;
constexpr int kWidth = 160, kHeight = 120;

struct Harness {
  explicit Harness(const std::string& clock, double latency, const std::function<void(CameraParams&)>& edit = {}) {
    m = LoadModelFromString("camera_worker_test", kSceneXml);
    d = mj_makeData(m.get());
    mj_forward(m.get(), d);
    DeviceConfig config;
    config.name = "webcam";
    config.kind = bridge::DeviceKind::kCamera;
    CameraParams& p = config.EditParams<CameraParams>();
    p.camera = "side";
    p.width = kWidth;
    p.height = kHeight;
    p.fps = 25;
    p.latency_s = latency;
    p.encoding = bridge::CameraEncoding::kRaw;  // no noise, no distortion: the pixels are the render's
    if (edit) edit(p);
    DeviceContext context;
    context.model = m.get();
    context.control_period_s = kPeriod;
    context.scene = "camera_worker_test";
    camera = SimCamera::Create(context, config);
    camera->Serve("127.0.0.1", 0, "test", clock);
    // subscribe while the test thread answers for the lab
    auto connected = std::async(std::launch::async, [this] {
      bridge::CameraClientOptions o;
      o.timeout_s = 5;
      return std::make_unique<bridge::CameraClient>(bridge::CameraClient::Connect("127.0.0.1", camera->port(), o));
    });
    while (connected.wait_for(std::chrono::milliseconds(1)) != std::future_status::ready) camera->PollRequests();
    client = connected.get();
    camera->BeforeRun(d);
  }
  ~Harness() {
    camera.reset();
    mj_deleteData(d);
  }
  ModelPtr m;
  mjData* d = nullptr;
  std::unique_ptr<SimCamera> camera;
  std::unique_ptr<bridge::CameraClient> client;
};

struct Sent {
  std::vector<long> frames_after_period;             // server frames counter after each period's Deliver
  std::vector<std::vector<std::uint8_t>> reference;  // the test thread's render of each frame's state
  std::vector<bridge::CameraClient::Frame> received;
};

// runs `periods` periods of free fall as the lab does (Deliver before the states go out,
// AfterPublish after), rendering a reference of each frame's state on this thread.
// `paced`: each period starts at its time on the wall clock, as a realtime lab's does
// (a realtime worker is given the wall time its frames need, not the time left between
// periods driven as fast as this thread can), and after the last period the lab goes on
// delivering at the last period's time until every frame is sent or counted dropped.
Sent Drive(Harness& h, int periods, bool paced = false) {
  Sent out;
  render::Renderer::Options o;
  o.width = kWidth;
  o.height = kHeight;
  o.log_renderer = false;
  auto renderer = render::Renderer::Create(h.m.get(), o);
  render::RgbImage image;
  const int cam = render::CameraId(h.m.get(), "side");
  const int steps = static_cast<int>(std::lround(kPeriod / h.m->opt.timestep));
  long next_frame = 0;  // frame n is stamped at the first period end at or after n / fps
  const auto start = std::chrono::steady_clock::now();
  const auto at = [&start](double t) {
    return start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(t));
  };
  for (int k = 0; k <= periods; ++k) {
    const double t = k * kPeriod;
    if (paced) std::this_thread::sleep_until(at(t));
    if (k > 0) {
      for (int s = 0; s < steps; ++s) mj_step(h.m.get(), h.d);
    }
    h.camera->Deliver(t, h.d);
    out.frames_after_period.push_back(h.camera->server()->counters().frames);
    h.camera->AfterPublish(h.d);
    while (next_frame / 25.0 <= t + 1e-9) {
      renderer->Render(h.d, cam, &image);
      out.reference.push_back(image.pixels);
      ++next_frame;
    }
  }
  if (paced) {
    // (bounded: a worker at nice 10 under a loaded machine still progresses; 20 s is
    // far beyond any frame's render)
    const double t_end = periods * kPeriod;
    for (int i = 0; i < 20000; ++i) {
      const long sent = h.camera->server()->counters().frames;
      if (sent + h.camera->frames_dropped() >= static_cast<long>(out.reference.size())) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      h.camera->Deliver(t_end, h.d);
    }
  }
  for (;;) {
    try {
      out.received.push_back(h.client->Receive(0.5));
    } catch (const bridge::TimeoutError&) {
      break;
    }
  }
  return out;
}

// the period index whose end is the first at or after stamp + latency
long DuePeriod(double stamp, double latency) {
  return static_cast<long>(std::ceil((stamp + latency) / kPeriod - 1e-9));
}

void ExpectFramesAreTheRendersOfTheirStates(const Sent& s) {
  ASSERT_GE(s.received.size(), 10u);
  for (std::size_t i = 0; i < s.received.size(); ++i) {
    const auto& f = s.received[i];
    EXPECT_EQ(f.id, static_cast<std::int64_t>(i));
    ASSERT_LT(static_cast<std::size_t>(f.id), s.reference.size());
    EXPECT_TRUE(f.rgb == s.reference[f.id]) << "frame " << f.id << ": not the render of its state";
  }
  EXPECT_NE(s.reference[0], s.reference[5]) << "the ball did not move: the test could not fail";
}

TEST(CameraWorkerTest, LockstepSendsEachFrameInItsPeriodWithItsStatesPixelsUnderLoad) {
  constexpr int kPeriods = 300;  // 0.6 s: 16 frames
  constexpr double kLatency = 0.01;
  std::vector<long> quiet_sent;
  for (const bool loaded : {false, true}) {
    // two threads that compete for both cores while the worker renders
    std::atomic<bool> stop{false};
    std::vector<std::thread> hogs;
    if (loaded) {
      for (int i = 0; i < 2; ++i) {
        hogs.emplace_back([&stop] {
          volatile double x = 0;
          while (!stop.load(std::memory_order_relaxed)) x = x + 1;
        });
      }
    }
    Harness h("lockstep", kLatency);
    const Sent s = Drive(h, kPeriods);
    stop = true;
    for (auto& t : hogs) t.join();
    ExpectFramesAreTheRendersOfTheirStates(s);
    ASSERT_EQ(s.received.size(), s.reference.size() - 1) << "every frame due by the end was sent";
    // sent in the period it became due, not a period later
    for (const auto& f : s.received) {
      const long due = DuePeriod(f.time_s, kLatency);
      ASSERT_LE(due, kPeriods);
      EXPECT_GE(s.frames_after_period[due], f.id + 1) << "frame " << f.id << " not sent by period " << due;
      if (due > 0) {
        EXPECT_LE(s.frames_after_period[due - 1], f.id) << "frame " << f.id << " sent early";
      }
    }
    EXPECT_EQ(h.camera->frames_late(), 0);
    if (!loaded) quiet_sent = s.frames_after_period;
    if (loaded) {
      EXPECT_EQ(s.frames_after_period, quiet_sent) << "the load changed which period sent a frame";
    }
  }
}

TEST(CameraWorkerTest, RealtimeNeverWaitsSendsEveryFrameInOrderAndCountsTheLateOnes) {
  constexpr int kPeriods = 300;
  constexpr double kLatency = 0.0;  // due the moment it is stamped: a frame can only be on time if
                                    // the worker finished it before Deliver looked
  Harness h("realtime", kLatency);
  const Sent s = Drive(h, kPeriods, /*paced=*/true);
  // each frame sent once, in order, with its state's pixels; the ones sent after their due
  // period are the late ones (the last, due in the last period, is always late: Deliver
  // never waits for the worker). A frame is dropped (never rendered, counted) only when
  // the worker is a whole ring of frames (0.2 s) behind. Every frame due is received or
  // counted dropped.
  ASSERT_EQ(s.reference.size(), 16u);  // stamps 0, 0.04, ..., 0.6 s
  EXPECT_EQ(static_cast<long>(s.received.size()) + h.camera->frames_dropped(), static_cast<long>(s.reference.size()))
      << "a frame was neither sent nor counted dropped";
  ASSERT_GE(s.received.size(), 10u) << "the worker fell a whole ring behind more than 6 times in 0.6 s";
  long late = 0;
  for (std::size_t i = 0; i < s.received.size(); ++i) {
    const auto& f = s.received[i];
    if (i > 0) {
      EXPECT_GT(f.id, s.received[i - 1].id) << "out of order or twice";
    }
    ASSERT_LT(static_cast<std::size_t>(f.id), s.reference.size());
    EXPECT_TRUE(f.rgb == s.reference[f.id]) << "frame " << f.id << ": not the render of its state";
    const long due = DuePeriod(f.time_s, kLatency);
    const bool on_time = s.frames_after_period[due] >= static_cast<long>(i) + 1;
    if (!on_time) ++late;
  }
  EXPECT_EQ(h.camera->frames_late(), late);
  EXPECT_GE(late, 1) << "the last frame, due in the last period, cannot have been done when it was queued";
}

}  // namespace
}  // namespace vlab::lab::camera_worker_test

namespace vlab::lab::camera_worker_test {
namespace {

// the camera's fault injection (drop_frames, late_frames, late_by), which tests of
// clients (the yo-yo controller, vlab vision) use: a dropped frame never goes out;
// a late frame goes out late_by after it was due, the frames due before that wait
// behind it (a stalled pipeline keeps its order) and are counted late with it
TEST(CameraWorkerTest, InjectedDropAndLateFramesGoOutAsConfigured) {
  constexpr int kPeriods = 300;  // 0.6 s: frames 0..15
  constexpr double kLatency = 0.01, kLateBy = 0.1;
  Harness h("lockstep", kLatency, [](CameraParams& p) {
    p.drop_frames = {3};
    p.late_frames = {6};
    p.late_by_s = kLateBy;
  });
  const Sent s = Drive(h, kPeriods);
  std::vector<std::int64_t> ids;
  for (const auto& f : s.received) ids.push_back(f.id);
  ASSERT_EQ(ids.size(), s.reference.size() - 2) << "all but the dropped frame, as in the fault-free test";
  for (std::size_t i = 0; i < ids.size(); ++i) {
    EXPECT_EQ(ids[i], static_cast<std::int64_t>(i < 3 ? i : i + 1)) << "in order, frame 3 missing";
    EXPECT_TRUE(s.received[i].rgb == s.reference[ids[i]]) << "frame " << ids[i] << ": not the render of its state";
  }
  // frame 6 (stamp 0.24 s) is due at 0.24 + 0.01 + 0.1 = 0.35 s: period 175
  const long held = DuePeriod(s.received[5].time_s, kLatency + kLateBy);
  ASSERT_EQ(s.received[5].id, 6);
  EXPECT_EQ(held, 175);
  EXPECT_LE(s.frames_after_period[held - 1], 5) << "frame 6 went out before its late_by had passed";
  // frames 7 and 8 (due at 0.29 and 0.33 s) went out with it, frame 9 (due 0.37 s) on time
  EXPECT_EQ(s.frames_after_period[held], 5 + 3);
  EXPECT_EQ(s.frames_after_period[DuePeriod(9 / 25.0, kLatency) - 1], 5 + 3);
  EXPECT_EQ(s.frames_after_period[DuePeriod(9 / 25.0, kLatency)], 5 + 4);
  EXPECT_EQ(h.camera->frames_late(), 3);     // 6, and 7 and 8 behind it
  EXPECT_EQ(h.camera->frames_dropped(), 1);  // 3
}

}  // namespace
}  // namespace vlab::lab::camera_worker_test

namespace vlab::lab::camera_worker_test {
namespace {

// the worker's scheduling once it has set it (it does so first thing): waits at most 5 s
bool WorkerScheduling(const SimCamera& camera, int* policy, int* nice) {
  for (int i = 0; i < 500 && camera.worker_thread_id() == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  const long tid = camera.worker_thread_id();
  if (tid == 0) return false;
  *policy = ::sched_getscheduler(static_cast<pid_t>(tid));
  errno = 0;
  *nice = ::getpriority(PRIO_PROCESS, static_cast<id_t>(tid));
  return true;
}

// the render worker runs below the control thread: nice 10 under a normal one, SCHED_FIFO
// one priority below a realtime one (so that no normal work, from any session, delays it)
TEST(CameraWorkerTest, TheWorkerRunsBelowTheControlThread) {
  std::thread normal([] {
    Harness h("realtime", 0.01);
    int policy = -1, nice = 99;
    Drive(h, 5);
    ASSERT_TRUE(WorkerScheduling(*h.camera, &policy, &nice));
    EXPECT_EQ(policy, SCHED_OTHER);
    EXPECT_EQ(nice, 10);
  });
  normal.join();
  std::thread fifo([] {
    if (!SetThreadRealtime(30)) {
      GTEST_SKIP() << "SCHED_FIFO is not permitted here: " << RealtimeRefusal(30, errno);
    }
    Harness h("realtime", 0.01);
    Drive(h, 5);
    int policy = -1, nice = 99;
    ASSERT_TRUE(WorkerScheduling(*h.camera, &policy, &nice));
    EXPECT_EQ(policy, SCHED_FIFO);
    sched_param p{};
    ASSERT_EQ(::sched_getparam(static_cast<pid_t>(h.camera->worker_thread_id()), &p), 0);
    EXPECT_EQ(p.sched_priority, 29);
  });
  fifo.join();
}

}  // namespace
}  // namespace vlab::lab::camera_worker_test
