#include "bridge/bridge_udp.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/address.hpp>
#include <boost/asio/ip/udp.hpp>

#include "bridge/bridge_errors.h"

namespace vlab::bridge {

namespace asio = boost::asio;

Endpoint::Endpoint() {
  std::memset(&storage_, 0, sizeof(storage_));
  storage_.v4.sin_family = AF_INET;
}

Endpoint Endpoint::FromSockaddr(const sockaddr* address, socklen_t size) {
  Endpoint e;
  if (address->sa_family == AF_INET && size >= static_cast<socklen_t>(sizeof(sockaddr_in))) {
    std::memcpy(&e.storage_.v4, address, sizeof(sockaddr_in));
  } else if (address->sa_family == AF_INET6 && size >= static_cast<socklen_t>(sizeof(sockaddr_in6))) {
    std::memcpy(&e.storage_.v6, address, sizeof(sockaddr_in6));
  }
  return e;
}

Endpoint::Address Endpoint::address() const {
  char text[INET6_ADDRSTRLEN + IF_NAMESIZE + 2] = {};
  if (storage_.any.sa_family == AF_INET) {
    ::inet_ntop(AF_INET, &storage_.v4.sin_addr, text, sizeof(text));
    return Address(false, text);
  }
  ::inet_ntop(AF_INET6, &storage_.v6.sin6_addr, text, sizeof(text));
  std::string out = text;
  // a scoped address names its interface (link-local) or its scope number, as Asio writes it
  if (const unsigned scope = storage_.v6.sin6_scope_id; scope != 0) {
    char name[IF_NAMESIZE + 1] = {};
    const in6_addr* a = &storage_.v6.sin6_addr;
    const bool link_local = IN6_IS_ADDR_LINKLOCAL(a) || IN6_IS_ADDR_MC_LINKLOCAL(a);
    out += "%" + (link_local && ::if_indextoname(scope, name) != nullptr ? std::string(name) : std::to_string(scope));
  }
  return Address(true, out);
}

int Endpoint::port() const {
  return ntohs(storage_.any.sa_family == AF_INET6 ? storage_.v6.sin6_port : storage_.v4.sin_port);
}

std::size_t Endpoint::AddressBytes(unsigned char* out) const {
  if (storage_.any.sa_family == AF_INET6) {
    std::memcpy(out, &storage_.v6.sin6_addr, 16);
    return 16;
  }
  std::memcpy(out, &storage_.v4.sin_addr, 4);
  return 4;
}

socklen_t Endpoint::size() const {
  return storage_.any.sa_family == AF_INET6 ? sizeof(sockaddr_in6) : sizeof(sockaddr_in);
}

bool operator==(const Endpoint& a, const Endpoint& b) {
  if (a.storage_.any.sa_family != b.storage_.any.sa_family) return false;
  if (a.storage_.any.sa_family == AF_INET6) {
    const sockaddr_in6 &x = a.storage_.v6, &y = b.storage_.v6;
    return x.sin6_port == y.sin6_port && x.sin6_scope_id == y.sin6_scope_id &&
           std::memcmp(&x.sin6_addr, &y.sin6_addr, sizeof(x.sin6_addr)) == 0;
  }
  const sockaddr_in &x = a.storage_.v4, &y = b.storage_.v4;
  return x.sin_port == y.sin_port && x.sin_addr.s_addr == y.sin_addr.s_addr;
}

namespace {

// conversions at the edge between the bridge's endpoint and Asio's
Endpoint FromAsio(const asio::ip::udp::endpoint& e) {
  return Endpoint::FromSockaddr(e.data(), static_cast<socklen_t>(e.size()));
}

asio::ip::udp::endpoint ToAsio(const Endpoint& e) {
  asio::ip::udp::endpoint a;
  std::memcpy(a.data(), e.data(), e.size());
  a.resize(e.size());
  return a;
}

}  // namespace

struct UdpSocket::Impl {
  asio::io_context io;
  asio::ip::udp::socket socket{io};
};

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

UdpSocket::UdpSocket() : impl_(std::make_unique<Impl>()) {}

UdpSocket::~UdpSocket() {
  boost::system::error_code ec;
  impl_->socket.close(ec);
}

Endpoint UdpSocket::MakeEndpoint(const std::string& address, int port) {
  boost::system::error_code ec;
  const asio::ip::address a = asio::ip::make_address(address, ec);
  if (ec) throw NetworkError("address '" + address + "': " + ec.message());
  if (port < 0 || port > 65535) throw NetworkError("port " + std::to_string(port) + " out of range 0..65535");
  return FromAsio(asio::ip::udp::endpoint(a, static_cast<unsigned short>(port)));
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
  const bool numeric = std::all_of(address.begin(), address.end(),
                                   [](char c) { return std::isdigit(static_cast<unsigned char>(c)) || c == '.'; });
  if (!name_chars || numeric) throw NetworkError("address '" + address + "' is neither an IP address nor a host name");
  asio::io_context io;
  asio::ip::udp::resolver resolver(io);
  boost::system::error_code ec;
  const auto results = resolver.resolve(address, std::to_string(port), ec);
  if (ec || results.empty()) {
    throw NetworkError("address '" + address + "': " + (ec ? ec.message() : std::string("no such host")));
  }
  for (const auto& r : results) {
    if (r.endpoint().address().is_v4()) return FromAsio(r.endpoint());
  }
  return FromAsio(results.begin()->endpoint());
}

std::unique_ptr<UdpSocket> UdpSocket::Bind(const std::string& address, int port) {
  const Endpoint at = MakeEndpoint(address, port);
  std::unique_ptr<UdpSocket> s(new UdpSocket());
  boost::system::error_code ec;
  asio::ip::udp::socket& socket = s->impl_->socket;
  const asio::ip::udp::endpoint asio_at = ToAsio(at);
  socket.open(asio_at.protocol(), ec);
  // close-on-exec: a program the lab starts (an external controller) must not
  // hold the lab's ports, nor read what is sent to them
  if (!ec && ::fcntl(socket.native_handle(), F_SETFD, FD_CLOEXEC) != 0) {
    ec = boost::system::error_code(errno, boost::system::system_category());
  }
  if (!ec) socket.bind(asio_at, ec);
  if (ec) throw NetworkError("cannot bind UDP " + EndpointText(at) + ": " + ec.message());
  socket.non_blocking(true, ec);
  s->local_ = FromAsio(socket.local_endpoint(ec));
  if (ec) throw NetworkError("UDP " + EndpointText(at) + ": " + ec.message());
  return s;
}

int UdpSocket::local_port() const { return local_.port(); }

int UdpSocket::fd() { return impl_->socket.native_handle(); }

bool UdpSocket::SendTo(const unsigned char* data, std::size_t size, const Endpoint& to) {
  // the socket is non-blocking: one try, with the flags Asio's send_to used on Linux
  return ::sendto(impl_->socket.native_handle(), data, size, MSG_NOSIGNAL, to.data(), to.size()) >= 0;
}

long UdpSocket::Receive(unsigned char* buffer, std::size_t capacity, Endpoint* from, double timeout_s,
                        bool* truncated) {
  if (truncated) *truncated = false;
  const int fd = impl_->socket.native_handle();
  if (timeout_s != 0 && !WaitReadable(&fd, 1, timeout_s)) return -1;
  // recvfrom with MSG_TRUNC reports the datagram's real size
  sockaddr_storage addr{};
  socklen_t len = sizeof(addr);
  const ssize_t n =
      ::recvfrom(fd, buffer, capacity, MSG_TRUNC | MSG_DONTWAIT, reinterpret_cast<sockaddr*>(&addr), &len);
  if (n < 0) return -1;
  if (from) *from = Endpoint::FromSockaddr(reinterpret_cast<const sockaddr*>(&addr), len);
  if (static_cast<std::size_t>(n) > capacity) {
    if (truncated) *truncated = true;
    return static_cast<long>(capacity);
  }
  return static_cast<long>(n);
}

}  // namespace vlab::bridge
