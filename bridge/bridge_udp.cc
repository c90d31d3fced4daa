#include "bridge/bridge_udp.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>

#include <boost/asio/ip/address.hpp>
#include <boost/asio/ip/udp.hpp>

#include "bridge/bridge_errors.h"

namespace vlab::bridge {

namespace asio = boost::asio;

bool WaitReadable(const int* fds, int count, double timeout_s) {
  pollfd p[kMaxWaitFds];
  const int n = count < kMaxWaitFds ? count : kMaxWaitFds;
  for (int i = 0; i < n; ++i) p[i] = pollfd{fds[i], POLLIN, 0};
  // ppoll: nanosecond timeouts (poll's milliseconds would make a 1 kHz loop late)
  timespec ts{};
  timespec* limit = nullptr;
  if (timeout_s >= 0) {
    ts.tv_sec = static_cast<time_t>(timeout_s);
    ts.tv_nsec = static_cast<long>((timeout_s - static_cast<double>(ts.tv_sec)) * 1e9);
    limit = &ts;
  }
  int ready;
  do {
    ready = ::ppoll(p, static_cast<nfds_t>(n), limit, nullptr);
  } while (ready < 0 && errno == EINTR);
  return ready > 0;
}

namespace {

int Granted(int fd, int option) {
  int value = 0;
  socklen_t length = sizeof(value);
  return ::getsockopt(fd, SOL_SOCKET, option, &value, &length) == 0 ? value : -1;
}

}  // namespace

int SetSocketBuffer(int fd, int option, int bytes) {
  ::setsockopt(fd, SOL_SOCKET, option, &bytes, sizeof(bytes));
  // the kernel reports twice the usable size it granted
  if (Granted(fd, option) < 2L * bytes) {
    const int force = option == SO_RCVBUF ? SO_RCVBUFFORCE : SO_SNDBUFFORCE;
    ::setsockopt(fd, SOL_SOCKET, force, &bytes, sizeof(bytes));  // fails without CAP_NET_ADMIN: fine
  }
  return Granted(fd, option);
}

std::string EndpointText(const Endpoint& e) {
  const std::string address = e.address().to_string();
  return (e.address().is_v6() ? "[" + address + "]" : address) + ":" + std::to_string(e.port());
}

UdpSocket::UdpSocket() : socket_(io_) {}

UdpSocket::~UdpSocket() {
  boost::system::error_code ec;
  socket_.close(ec);
}

Endpoint UdpSocket::MakeEndpoint(const std::string& address, int port) {
  boost::system::error_code ec;
  const asio::ip::address a = asio::ip::make_address(address, ec);
  if (ec) throw NetworkError("address '" + address + "': " + ec.message());
  if (port < 0 || port > 65535) throw NetworkError("port " + std::to_string(port) + " out of range 0..65535");
  return Endpoint(a, static_cast<unsigned short>(port));
}

Endpoint UdpSocket::Resolve(const std::string& address, int port) {
  if (port < 1 || port > 65535) throw NetworkError("port " + std::to_string(port) + " out of range 1..65535");
  try {
    return MakeEndpoint(address, port);
  } catch (const NetworkError&) {
  }
  // a host name: letters, digits, '-' and '.', not all digits (no DNS query for "300.1.2.3")
  const bool name_chars = !address.empty() && std::all_of(address.begin(), address.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '.';
  });
  const bool numeric = std::all_of(address.begin(), address.end(), [](char c) {
    return std::isdigit(static_cast<unsigned char>(c)) || c == '.';
  });
  if (!name_chars || numeric) throw NetworkError("address '" + address + "' is neither an IP address nor a host name");
  asio::io_context io;
  asio::ip::udp::resolver resolver(io);
  boost::system::error_code ec;
  const auto results = resolver.resolve(address, std::to_string(port), ec);
  if (ec || results.empty()) {
    throw NetworkError("address '" + address + "': " + (ec ? ec.message() : std::string("no such host")));
  }
  for (const auto& r : results) {
    if (r.endpoint().address().is_v4()) return r.endpoint();
  }
  return results.begin()->endpoint();
}

std::unique_ptr<UdpSocket> UdpSocket::Bind(const std::string& address, int port) {
  const Endpoint at = MakeEndpoint(address, port);
  std::unique_ptr<UdpSocket> s(new UdpSocket());
  boost::system::error_code ec;
  s->socket_.open(at.protocol(), ec);
  // close-on-exec: a program the lab starts (an external controller) must not
  // hold the lab's ports, nor read what is sent to them
  if (!ec && ::fcntl(s->socket_.native_handle(), F_SETFD, FD_CLOEXEC) != 0) {
    ec = boost::system::error_code(errno, boost::system::system_category());
  }
  if (!ec) s->socket_.bind(at, ec);
  if (ec) throw NetworkError("cannot bind UDP " + EndpointText(at) + ": " + ec.message());
  s->socket_.non_blocking(true, ec);
  s->local_ = s->socket_.local_endpoint(ec);
  if (ec) throw NetworkError("UDP " + EndpointText(at) + ": " + ec.message());
  return s;
}

int UdpSocket::local_port() const { return local_.port(); }

int UdpSocket::fd() { return socket_.native_handle(); }

bool UdpSocket::SendTo(const unsigned char* data, std::size_t size, const Endpoint& to) {
  boost::system::error_code ec;
  socket_.send_to(asio::buffer(data, size), to, 0, ec);
  return !ec;
}

long UdpSocket::Receive(unsigned char* buffer, std::size_t capacity, Endpoint* from, double timeout_s,
                        bool* truncated) {
  if (truncated) *truncated = false;
  const int fd = socket_.native_handle();
  if (timeout_s != 0 && !WaitReadable(&fd, 1, timeout_s)) return -1;
  // recvfrom with MSG_TRUNC reports the datagram's real size
  sockaddr_storage addr{};
  socklen_t len = sizeof(addr);
  const ssize_t n = ::recvfrom(fd, buffer, capacity, MSG_TRUNC | MSG_DONTWAIT, reinterpret_cast<sockaddr*>(&addr), &len);
  if (n < 0) return -1;
  if (from) {
    from->resize(len);
    std::memcpy(from->data(), &addr, len);
  }
  if (static_cast<std::size_t>(n) > capacity) {
    if (truncated) *truncated = true;
    return static_cast<long>(capacity);
  }
  return static_cast<long>(n);
}

}  // namespace vlab::bridge
