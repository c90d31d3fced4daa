// A camera device for the clients in other languages (the Python client's
// test): serves frames with a known pattern through CameraServer on 127.0.0.1.
//
//   test_camera_server [--frames N] [--width W] [--height H] [--encoding raw|jpeg]
//                      [--fps F] [--drop P] [--seed S] [--chunk-bytes B]
//
// Prints "listening 127.0.0.1:PORT", waits (up to 10 s) for a subscriber,
// sends N frames at F Hz (raw: byte i of frame k = (7 i + 13 (i >> 8) + 31 k)
// mod 256; jpeg: a smooth gradient), printing "frame K whole" or "frame K
// damaged" (chunks dropped by the test hook, seeded), then "done", and keeps
// answering requests for one more second.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "bridge/bridge_camera_server.h"
#include "camera_test_util.h"

int main(int argc, char** argv) {
  using Clock = std::chrono::steady_clock;
  int frames = 10, width = 160, height = 120, chunk_bytes = 60000;
  double fps = 30, drop = 0;
  unsigned long seed = 1;
  std::string encoding = "raw";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string option = argv[i];
    const char* value = argv[i + 1];
    if (option == "--frames")
      frames = std::atoi(value);
    else if (option == "--width")
      width = std::atoi(value);
    else if (option == "--height")
      height = std::atoi(value);
    else if (option == "--encoding")
      encoding = value;
    else if (option == "--fps")
      fps = std::atof(value);
    else if (option == "--drop")
      drop = std::atof(value);
    else if (option == "--seed")
      seed = std::strtoul(value, nullptr, 10);
    else if (option == "--chunk-bytes")
      chunk_bytes = std::atoi(value);
    else {
      std::fprintf(stderr, "test_camera_server: unknown option %s\n", option.c_str());
      return 2;
    }
  }
  vlab::bridge::CameraServerConfig config;
  config.description.name = "pattern";
  config.description.server = "test_camera_server";
  config.description.source = "test pattern";
  config.description.pose = "fixed";
  config.description.width = width;
  config.description.height = height;
  config.description.fps = fps;
  config.description.fx = config.description.fy = width;
  config.description.cx = width / 2.0 - 0.5;
  config.description.cy = height / 2.0 - 0.5;
  vlab::bridge::EncodingFromName(encoding, &config.description.encoding);
  config.chunk_bytes = static_cast<std::size_t>(chunk_bytes);
  config.test_drop_probability = drop;
  config.test_drop_seed = seed;
  auto server = vlab::bridge::CameraServer::Create(config);
  std::printf("listening 127.0.0.1:%d\n", server->port());
  std::fflush(stdout);

  const Clock::time_point give_up = Clock::now() + std::chrono::seconds(10);
  while (server->subscribers() == 0 && Clock::now() < give_up) server->Poll(0.05);
  std::vector<std::uint8_t> rgb(3u * width * height);
  const Clock::time_point start = Clock::now();
  vlab::bridge::CameraPose pose;
  pose.valid = true;
  pose.p_WC = Eigen::Vector3d(0.5, 0, 1.2);
  pose.q_WC = Eigen::Quaterniond(0, 1, 0, 0);
  for (int k = 0; k < frames; ++k) {
    const Clock::time_point due = start + std::chrono::microseconds(static_cast<long>(k * 1e6 / fps));
    while (Clock::now() < due) server->Poll(std::chrono::duration<double>(due - Clock::now()).count());
    if (encoding == "raw") {
      vlab::testing::FillPattern(k, &rgb);
    } else {
      for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
          std::uint8_t* p = rgb.data() + 3 * (static_cast<std::size_t>(y) * width + x);
          p[0] = static_cast<std::uint8_t>(x + k);
          p[1] = static_cast<std::uint8_t>(y);
          p[2] = 128;
        }
      }
    }
    const long damaged = server->counters().test_damaged_frames;
    server->SendImage(k, k / fps, rgb.data(), pose);
    std::printf("frame %d %s\n", k, server->counters().test_damaged_frames > damaged ? "damaged" : "whole");
  }
  std::printf("done\n");
  std::fflush(stdout);
  const Clock::time_point linger = Clock::now() + std::chrono::seconds(1);
  while (Clock::now() < linger) server->Poll(0.05);
  return 0;
}
