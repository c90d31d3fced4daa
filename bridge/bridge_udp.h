// A UDP socket for the bridge (Boost.Asio underneath), with the two calls the
// bridge needs: send a datagram to an endpoint, and receive one datagram with a
// time limit. Receive and send never throw: they return a status.
#pragma once

#include <cstddef>
#include <memory>
#include <string>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/udp.hpp>

namespace vlab::bridge {

using Endpoint = boost::asio::ip::udp::endpoint;

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
  UdpSocket();
  boost::asio::io_context io_;
  boost::asio::ip::udp::socket socket_;
  Endpoint local_;
};

}  // namespace vlab::bridge
