// What the vision programs' devices share (the markers device,
// vision_server.h; the yoyo device, vision_yoyo_server.h): the name, the UDP
// socket, the subscribers' limits and the facts merged into the describe reply.
#pragma once

#include <memory>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "bridge/bridge_device_server.h"

namespace vlab::vision {

/// A vision program's device: its name and socket. Each device's config
/// derives from it and gives its own default name and port.
struct VisionDeviceConfig {
  /// The device's defaults: its name in describe replies and its UDP port.
  VisionDeviceConfig(std::string default_name, int default_port) : name(std::move(default_name)), port(default_port) {}

  std::string name;
  std::string bind_address = "127.0.0.1";
  int port;  ///< 0: any free port
  double subscriber_timeout_s = 10;
  int max_subscribers = 16;
  /// Facts merged into the describe reply (camera, detector or tracker, rates).
  nlohmann::json describe_extra = nlohmann::json::object();
};

/// Binds the device's UDP socket at bind_address:port, every datagram queued
/// for the device's Poll. Throws bridge::NetworkError naming the address when it cannot.
inline std::unique_ptr<bridge::DeviceServer> BindDeviceSocket(const VisionDeviceConfig& config) {
  bridge::DeviceServerConfig s;
  s.bind_address = config.bind_address;
  s.port = config.port;
  s.max_datagrams = 0;  // every datagram queued
  return bridge::DeviceServer::Bind(s);
}

}  // namespace vlab::vision
