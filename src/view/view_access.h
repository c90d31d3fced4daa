// Which Host and Origin headers `vlab view` answers (view_server.h): the
// defence against a web page in the user's browser reading the view, by a
// cross-origin WebSocket (a foreign Origin) or by DNS rebinding (a foreign
// name in Host that resolves to this machine).
//
// Allowed names, with or without a port (the port is never compared: an ssh
// -L forward serves the page on another port than the server's):
//   - localhost, 127.0.0.0/8 and [::1] (loopback);
//   - the address the server is bound to, as a literal;
//   - when bound to every address (0.0.0.0, ::), any IP address literal: a
//     rebinding page always names a host, never an address;
//   - the names given (vlab view --allow-host NAME), compared without case.
// An Origin is also allowed when it equals, without case, a whole origin
// given (vlab view --allow-origin https://app.foxglove.dev: a web app of
// another site that the user lets read the view, scheme and port compared).
// Anything else is refused: a bad Host with 421, a bad Origin with 403. A
// request without Host or Origin (not a browser: browsers send Host always
// and Origin on every WebSocket upgrade) is not refused for their absence.
#pragma once

#include <string>
#include <vector>

namespace vlab::view {

struct AccessPolicy {
  std::string bound;                         ///< the address bound, as asio prints it ("127.0.0.1", "::")
  std::vector<std::string> allowed_hosts;    ///< names allowed beside the loopback ones (--allow-host)
  std::vector<std::string> allowed_origins;  ///< whole origins allowed in Origin (--allow-origin)
};

/// True when a Host header's value names this server (see the file comment).
/// Malformed values (an unbracketed IPv6 address, a port that is not 1-5
/// digits, an empty name) are false.
bool HostAllowed(const AccessPolicy& policy, const std::string& host);

/// True when an Origin header's value ("http://NAME[:PORT]", https too) names
/// an allowed host. "null", other schemes and values with a path are false.
bool OriginAllowed(const AccessPolicy& policy, const std::string& origin);

/// True when `origin` is "http://" or "https://" then a host as Host names
/// it (with or without a port), and nothing else (no path, no userinfo):
/// what --allow-origin accepts.
bool ValidOrigin(const std::string& origin);

/// True when `address` (an IP literal) is loopback: 127.0.0.0/8, ::1, or an
/// IPv4-mapped loopback. False for anything that is not an address.
bool IsLoopbackAddress(const std::string& address);

/// An address as a URL's host: IPv6 in brackets ("[::1]"), others as given.
std::string UrlHost(const std::string& address);

}  // namespace vlab::view
