// vlab view: a live 3-D view of the lab in the browser (src/view/), from a
// scene device, from an arm device's joint states, or from a recorded run.
#include <cstdio>
#include <memory>

#include "bridge/bridge_signals.h"
#include "cli/cli_commands.h"
#include "view/view_gltf.h"
#include "view/view_program.h"

namespace vlab::cli {

Subcommand AddViewCommand(CLI::App& app) {
  auto o = std::make_shared<view::ViewOptions>();
  CLI::App* cmd = app.add_subcommand(
      "view",
      "Serve a live 3-D view of the lab to a browser (HTTP + WebSocket, three.js): from a scene device, "
      "an arm device, or a recorded run; read-only");
  cmd->add_option("--scene", o->scene, "Scene device to draw, HOST:PORT (a scenario's kind: scene device)");
  cmd->add_option("--arm", o->arm,
                  "Arm device to draw instead, HOST:PORT (vlab serve, vlab-kinsim or a real arm's driver): poses "
                  "from its joint states by MuJoCo kinematics of --model");
  cmd->add_option("--replay", o->replay, "A run's output folder with scene.json and poses.bin, to replay");
  cmd->add_option("--model", o->model,
                  "MJCF scene for meshes, textures and cameras (--arm: required; --scene, --replay: default the "
                  "one the device or recording names)");
  cmd->add_option("--rate", o->rate_hz,
                  "--arm: pose frames and plot samples per second (default 30; --scene: the device's rate)");
  cmd->add_option("--camera", o->camera,
                  "Camera device, HOST:PORT: its pictures in a panel, newest first (JPEG relayed as sent, raw as PNG)");
  cmd->add_option("--plot", o->plot,
                  "Signals to plot, comma-separated log.csv column names (at most 8), e.g. pa10.q.S1,pa10.qd.S1: "
                  "--scene: among the scene device's signals (its scenario entry's signals: [...]); --arm: the arm's "
                  "ARM.q.JOINT, ARM.qd.JOINT, ARM.tau.JOINT; --replay: any column of the run's log.csv");
  cmd->add_option("--http", o->server.port, "TCP port of the page (default 8080; 0: any free port)");
  cmd->add_option(
      "--foxglove", o->foxglove_port,
      "Also serve the Foxglove WebSocket protocol (foxglove.websocket.v1) on this TCP port (0: any free "
      "port; printed), for Foxglove or Lichtblick (Open connection, Foxglove WebSocket, ws://localhost:PORT): "
      "/tf, /scene, one channel per device of the signals the view gets (--scene: the scene device's signals; "
      "--arm: the arm's q, qd, tau), /camera/NAME with --camera; ROS 2 messages (cdr). Read-only; --bind, "
      "--allow-host, --allow-origin and the bounds apply to it as to the page (docs/view.md)");
  cmd->add_option("--bind", o->server.bind,
                  "Address the page binds to (default 127.0.0.1; from another machine use ssh -L, see docs/view.md; "
                  "beyond loopback anyone who can reach the port can watch, and vlab view says so on stderr)");
  cmd->add_option("--allow-host", o->server.allowed_hosts,
                  "A name the page may be opened by (Host and Origin), beside localhost, 127.0.0.0/8, [::1] and the "
                  "--bind address; repeatable. Any other name is refused (421, 403): a web page elsewhere cannot read "
                  "the view, by a cross-origin WebSocket or by DNS rebinding");
  cmd->add_option("--allow-origin", o->server.allowed_origins,
                  "A whole origin whose pages may read the view and the Foxglove stream (Origin header), e.g. "
                  "https://app.foxglove.dev for Foxglove in the browser; repeatable. Clients that send no Origin (the "
                  "Foxglove and Lichtblick desktop apps) need none");
  cmd->add_option("--max-connections", o->server.max_connections,
                  "WebSocket sessions served at once (a tab takes one, two or three: poses, camera, plot) (default 64; "
                  "more are closed at once with 'server full', which the page shows)");
  cmd->add_option("--max-per-address", o->server.max_per_address,
                  "WebSocket sessions, and HTTP connections, from one address at once (default 32). HTTP connections: "
                  "128 at once; a request head must come whole within 5 s; when full, a new connection closes the one "
                  "that has waited longest for its request. A WebSocket that does not read is closed (no pong in 10 s, "
                  "or a frame not taken in 5 s)");
  cmd->add_flag_function(
      "--no-shadows", [o](std::int64_t) { o->shadows = false; },
      "The page starts without shadows (default: the MJCF's lights with castshadow cast them; the "
      "page's 'shadows' box, or ?shadows=off in its address, turns them off and on)");
  cmd->add_option("--web", o->web, "Folder of the page's files (default: view_web beside the vlab binary)");
  cmd->add_option("--connect-timeout", o->connect_timeout_s, "Wait this long for the device, s (default 10)");
  cmd->add_option("--duration", o->duration_s, "Stop after this many seconds (default: run until interrupted)");
  cmd->add_flag("-q,--quiet", o->quiet, "Only the start line and the final counter line");
  return {cmd, [o] {
            return WithErrorReport([&] {
              // SIGINT, SIGTERM: the view stops serving and prints its counters; installed before it
              // connects to its device, so that one during the wait is not lost
              InstallStopSignals();
              return view::RunView(*o, &g_stop_requested);
            });
          }};
}

}  // namespace vlab::cli

namespace vlab::cli {

Subcommand AddExportCommand(CLI::App& app) {
  struct Args {
    std::string run, glb, model;
  };
  auto a = std::make_shared<Args>();
  CLI::App* cmd =
      app.add_subcommand("export",
                         "Write a run's recorded poses (outputs: {poses: ...}) as glTF 2.0 (.glb) with animation, for "
                         "Blender and three.js: the geoms with their colours and textures (PNG inside the .glb), the "
                         "MJCF's cameras and its lights (KHR_lights_punctual); docs/view.md says what maps how");
  cmd->add_option("run", a->run, "The run's output folder (with scene.json and poses.bin)")->required();
  cmd->add_option("file", a->glb, "The .glb file to write (never overwritten)")->required();
  cmd->add_option("--model", a->model,
                  "MJCF for meshes, textures, cameras and lights (default: the one scene.json names; without one "
                  "found, a scene without meshes or textures is exported without cameras and lights)");
  return {cmd, [a] {
            return WithErrorReport([&] {
              const view::GltfSummary s = view::ExportGltf(a->run, a->glb, a->model);
              std::printf(
                  "vlab export: %s: %d bodies, %d geoms, %d textures, %d cameras, %d lights, %ld frames over %.3f s, "
                  "%ld bytes\n",
                  a->glb.c_str(), s.bodies, s.geoms, s.textures, s.cameras, s.lights, s.frames, s.duration_s, s.bytes);
              if (s.left_out > 0) {
                std::printf("vlab export: %d cameras or lights left out: their bodies move and are not recorded\n",
                            s.left_out);
              }
              return 0;
            });
          }};
}

}  // namespace vlab::cli
