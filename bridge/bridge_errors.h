// Errors of the bridge's client side: a small typed hierarchy.
//   BridgeError            any bridge failure (catch this for all)
//   ├─ NetworkError        a socket could not be opened, bound or used
//   ├─ ProtocolError       a reply was not a valid vlab packet (or not the expected kind)
//   │   └─ VersionMismatch the peer speaks another protocol version
//   ├─ TimeoutError        nothing arrived within the time given
//   └─ RefusedError        the device answered that it refused a request (an arm's payload)
// The device side never throws in its real-time path: it counts faults.
#pragma once

#include <cstdio>
#include <stdexcept>
#include <string>

namespace vlab::bridge {

class BridgeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
class NetworkError : public BridgeError {
 public:
  using BridgeError::BridgeError;
};
class ProtocolError : public BridgeError {
 public:
  using BridgeError::BridgeError;
};
class VersionMismatch : public ProtocolError {
 public:
  using ProtocolError::ProtocolError;
};
class TimeoutError : public BridgeError {
 public:
  using BridgeError::BridgeError;
};
class RefusedError : public BridgeError {
 public:
  using BridgeError::BridgeError;
};

/// A number as the errors' messages print it (%g: six significant digits), and "N s".
inline std::string ErrorNumber(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}
inline std::string ErrorSeconds(double s) { return ErrorNumber(s) + " s"; }

}  // namespace vlab::bridge
