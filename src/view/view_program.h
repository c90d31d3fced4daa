// `vlab view`'s program: one pose source (a scene device, an arm device and
// the MJCF, or a recorded run) feeding the HTTP/WebSocket server.
#pragma once

#include <csignal>
#include <memory>
#include <string>

#include "view/view_server.h"

namespace vlab::view {

struct ViewOptions {
  std::string scene;    ///< HOST:PORT of a scene device (live)
  std::string arm;      ///< HOST:PORT of an arm device (live, poses by MuJoCo kinematics of `model`)
  std::string replay;   ///< a run's output folder with scene.json and poses.bin
  std::string model;    ///< MJCF for meshes, textures, cameras (--arm: required; --scene: default the describe reply's)
  double rate_hz = 30;  ///< --arm: pose frames and plot samples per second
  std::string camera;   ///< HOST:PORT of a camera device: its pictures in a panel (live only)
  std::string plot;     ///< signals to plot, comma-separated log.csv names ("pa10.q.S1,pa10.q.E1")
  std::string web;      ///< the page's folder (default: view_web beside the executable)
  int foxglove_port = -1;  ///< a Foxglove WebSocket server on this port beside the page (0: any free; -1: none)
  ViewServerConfig server;
  double connect_timeout_s = 10;
  double duration_s = 0;  ///< stop after this long (0: until a signal)
  bool shadows = true;    ///< the page casts shadows (a switch on the page turns them off and on)
  bool quiet = false;
};

/// Runs the view until *stop is set or the duration ends; prints a start line
/// ("vlab view: http://ADDRESS:PORT/ ...", an IPv6 address in brackets; with
/// --foxglove, "...; foxglove ws://ADDRESS:PORT (N channels)" ends it), a
/// warning on stderr when bound beyond loopback, and a counter line. Throws
/// InputError (exit 2) for bad options, a missing page file or model, an
/// unreadable recording; bridge errors when the device does not answer.
int RunView(const ViewOptions& options, volatile std::sig_atomic_t* stop);

/// "HOST:PORT" -> host and port (1..65535); throws InputError naming `option`.
void SplitHostPort(const std::string& option, const std::string& text, std::string* host, int* port);

}  // namespace vlab::view
