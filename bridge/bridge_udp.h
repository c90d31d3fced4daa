// A UDP socket for the bridge, with the two calls the bridge needs: send a
// datagram to an endpoint, and receive one datagram with a time limit. Receive
// and send never throw: they return a status. Boost.Asio (address parsing,
// name lookup) stays inside bridge_udp.cc: an Endpoint is the socket API's own
// address, so a header that names one does not pull Asio into its includers.
#pragma once

#include <netinet/in.h>
#include <sys/socket.h>

#include <cstddef>
#include <memory>
#include <string>
#include <utility>

namespace vlab::bridge {

/// A UDP peer: an IPv4 or IPv6 address and a port, kept as the kernel's
/// socket address: a small value type, copied freely, and what sendto and
/// recvfrom take, so the hot path converts nothing.
class Endpoint {
 public:
  /// An endpoint's address alone: its family and numeric text.
  class Address {
   public:
    /// The family: IPv4 or IPv6.
    bool is_v4() const { return !v6_; }
    bool is_v6() const { return v6_; }
    /// "127.0.0.1", "::1", "fe80::1%eth0" (without brackets or port).
    std::string to_string() const { return text_; }

   private:
    friend class Endpoint;
    Address(bool v6, std::string text) : v6_(v6), text_(std::move(text)) {}
    bool v6_;
    std::string text_;
  };

  /// 0.0.0.0 port 0: what Receive overwrites.
  Endpoint();
  /// The endpoint of a kernel socket address (AF_INET or AF_INET6, `size`
  /// bytes); any other family gives the default endpoint.
  static Endpoint FromSockaddr(const sockaddr* address, socklen_t size);

  /// The address without the port ("127.0.0.1" through to_string()).
  Address address() const;
  /// The port, host byte order (0..65535).
  int port() const;
  /// Copies the address's bytes, network order, into out (room for 16):
  /// 4 for IPv4, 16 for IPv6; returns how many.
  std::size_t AddressBytes(unsigned char* out) const;
  /// The kernel socket address, for sendto and bind, and its size in bytes.
  const sockaddr* data() const { return &storage_.any; }
  socklen_t size() const;

  /// Same family, address (with the IPv6 scope) and port.
  friend bool operator==(const Endpoint& a, const Endpoint& b);
  friend bool operator!=(const Endpoint& a, const Endpoint& b) { return !(a == b); }

 private:
  union Storage {
    sockaddr any;
    sockaddr_in v4;
    sockaddr_in6 v6;
  };
  Storage storage_;
};

/// Bytes of a receive buffer that any UDP datagram fits (IPv4 and IPv6 payloads are at most 65,535 bytes).
inline constexpr std::size_t kDatagramBufferBytes = 65536;

/// Most file descriptors WaitReadable watches (the rest are ignored).
inline constexpr int kMaxWaitFds = 64;

/// Waits up to timeout_s (< 0: forever) until one of the file descriptors
/// (sockets' fd(), at most kMaxWaitFds) is readable; false on timeout.
bool WaitReadable(const int* fds, int count, double timeout_s);

/// Asks for a `bytes`-byte buffer (option SO_RCVBUF or SO_SNDBUF) on socket
/// `fd`: first within the system limit (net.core.rmem_max / wmem_max), then,
/// if the kernel granted less and the process may (CAP_NET_ADMIN), with
/// SO_RCVBUFFORCE / SO_SNDBUFFORCE. Returns the size the kernel reports
/// (Linux doubles the request to account for its bookkeeping), or -1.
/// Camera streams need it (a raw 640x480 frame is 16 chunks of 60 kB sent
/// back to back; the default 208 KiB holds about three), and so does a
/// device that must ride out a burst of datagrams.
int SetSocketBuffer(int fd, int option, int bytes);

/// "ADDR:PORT" of an endpoint, for messages.
std::string EndpointText(const Endpoint& endpoint);

class UdpSocket {
 public:
  /// Opens a socket bound to address:port (port 0: any free port). Throws
  /// NetworkError naming the address when it cannot.
  static std::unique_ptr<UdpSocket> Bind(const std::string& address, int port);
  /// Resolves a numeric IPv4/IPv6 address and port; throws NetworkError.
  static Endpoint MakeEndpoint(const std::string& address, int port);
  /// A device's address: a numeric address first, then a host name lookup (IPv4
  /// preferred); port 1..65535. Throws NetworkError naming the address.
  static Endpoint Resolve(const std::string& address, int port);
  ~UdpSocket();

  int local_port() const;
  /// The socket's file descriptor, for WaitReadable over several sockets.
  int fd();
  const Endpoint& local_endpoint() const { return local_; }

  /// Sends one datagram; false on error.
  bool SendTo(const unsigned char* data, std::size_t size, const Endpoint& to);
  /// Waits up to timeout_s (0: do not wait, < 0: wait forever) for one
  /// datagram; returns its size (copied into buffer, truncated to capacity), or
  /// -1 if none arrived. *truncated is set when the datagram was larger.
  long Receive(unsigned char* buffer, std::size_t capacity, Endpoint* from, double timeout_s,
               bool* truncated = nullptr);

 private:
  struct Impl;  // the Asio socket
  UdpSocket();
  std::unique_ptr<Impl> impl_;
  Endpoint local_;
};

}  // namespace vlab::bridge
