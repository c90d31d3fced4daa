// Renderers on several threads at once (render/renderer.h, "Threads"): each
// renderer made and used on its own thread draws exactly the pixels that one
// renderer on the test's thread draws of the same states. This is what lets
// the lab render served cameras on worker threads, off its control thread.
#include <array>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "render_test_scene.h"

namespace vlab::testing {
namespace {

class RendererThreadsTest : public RenderScene {
 protected:
  // the scene's states: the ball at a few places, kept as copies of mjData
  std::vector<mjData*> States(int n) {
    std::vector<mjData*> states;
    for (int i = 0; i < n; ++i) {
      Place("ball", 0.1 * (i % 5) - 0.2, 0.05 * (i % 3), 0.3 + 0.02 * i);
      mjData* copy = MakeData(m_);
      mj_copyData(copy, m_, d_);
      states.push_back(copy);
    }
    return states;
  }
};

TEST_F(RendererThreadsTest, TwoThreadsAtOnceDrawWhatOneThreadDraws) {
  constexpr int kFrames = 12;
  const std::vector<mjData*> states = States(kFrames);
  const int cam = render::CameraId(m_, "tilted");
  render::Renderer::Options o;
  o.width = 160;
  o.height = 120;
  o.log_renderer = false;

  // reference: one renderer on this thread
  std::vector<render::RgbImage> reference(kFrames);
  {
    auto r = render::Renderer::Create(m_, o);
    for (int i = 0; i < kFrames; ++i) r->Render(states[i], cam, &reference[i]);
  }
  // two threads, each with its own renderer, drawing the same frames at the same time, twice over
  std::array<std::vector<render::RgbImage>, 2> drawn;
  std::vector<std::thread> threads;
  for (int t = 0; t < 2; ++t) {
    threads.emplace_back([&, t] {
      auto r = render::Renderer::Create(m_, o);
      drawn[t].resize(2 * kFrames);
      for (int i = 0; i < 2 * kFrames; ++i) r->Render(states[i % kFrames], cam, &drawn[t][i]);
    });
  }
  for (auto& th : threads) th.join();
  for (int t = 0; t < 2; ++t) {
    for (int i = 0; i < 2 * kFrames; ++i) {
      EXPECT_EQ(drawn[t][i].pixels, reference[i % kFrames].pixels) << "thread " << t << ", frame " << i;
    }
  }
  // and the frames differ from each other: the ball moved (a test that could not fail otherwise)
  EXPECT_NE(reference[0].pixels, reference[1].pixels);
}

}  // namespace
}  // namespace vlab::testing
