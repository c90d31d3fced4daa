// The clients of view_clients.h on Boost.Asio and Boost.Beast: a raw TCP
// socket read with poll(2), and a Beast WebSocket stream whose errors become
// WsError with Boost's message.
#include "view_clients.h"

#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <map>
#include <utility>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>

namespace vlab::view::view_test {

namespace asio = boost::asio;
namespace beast = boost::beast;
using tcp = asio::ip::tcp;

std::unique_ptr<ViewServer> StartServer(ViewServerConfig config) {
  config.port = 0;
  std::map<std::string, StaticFile> files{{"/index.html", {"text/html", kPage}},
                                          {"/view.js", {"text/javascript", "//"}}};
  auto resources = [](const std::string& path, std::string* type, std::string* body) {
    if (path != "/scene.json") return false;
    *type = "application/json";
    *body = "{}";
    return true;
  };
  return ViewServer::Create(config, std::move(files), resources);
}

struct Raw::Impl {
  asio::io_context io;
  tcp::socket socket{io};
};

Raw::Raw(int port, const std::string& source) : impl_(std::make_unique<Impl>()) {
  impl_->socket.open(tcp::v4());
  if (!source.empty()) impl_->socket.bind({asio::ip::make_address(source), 0});
  impl_->socket.connect({asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)});
}

Raw::~Raw() = default;

Raw& Raw::Send(const std::string& bytes) {
  boost::system::error_code ec;
  asio::write(impl_->socket, asio::buffer(bytes), ec);  // the server may close before all is sent
  return *this;
}

std::string Raw::ReadAll(double timeout_s) {
  std::string out;
  closed_ = false;
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  char buffer[4096];
  while (std::chrono::steady_clock::now() < end) {
    pollfd p{impl_->socket.native_handle(), POLLIN, 0};
    if (::poll(&p, 1, 50) <= 0) continue;
    const ssize_t n = ::recv(impl_->socket.native_handle(), buffer, sizeof(buffer), 0);
    if (n <= 0) {
      closed_ = true;
      break;
    }
    out.append(buffer, static_cast<std::size_t>(n));
  }
  return out;
}

std::string Get(int port, const std::string& target, const std::string& extra) {
  return Raw(port)
      .Send("GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\n" + extra + "Connection: close\r\n\r\n")
      .ReadAll();
}

struct WsClient::Impl {
  asio::io_context io;
  beast::websocket::stream<tcp::socket> ws{io};
};

WsClient::WsClient(int port, const std::string& path, const std::string& origin, const std::string& source)
    : WsClient(port, [&] {
        WsOptions options;
        options.path = path;
        options.origin = origin;
        options.source = source;
        return options;
      }()) {}

WsClient::WsClient(int port, const WsOptions& options) : impl_(std::make_unique<Impl>()) {
  beast::websocket::stream<tcp::socket>& ws = impl_->ws;
  try {
    ws.next_layer().open(tcp::v4());
    if (!options.source.empty()) ws.next_layer().bind({asio::ip::make_address(options.source), 0});
    ws.next_layer().connect({asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)});
    if (options.read_timeout.count() > 0) {
      const timeval limit{static_cast<time_t>(options.read_timeout.count()), 0};
      ::setsockopt(ws.next_layer().native_handle(), SOL_SOCKET, SO_RCVTIMEO, &limit, sizeof(limit));
    }
    if (!options.origin.empty() || !options.subprotocol.empty()) {
      ws.set_option(beast::websocket::stream_base::decorator(
          [origin = options.origin, protocol = options.subprotocol](beast::websocket::request_type& r) {
            if (!origin.empty()) r.set(beast::http::field::origin, origin);
            if (!protocol.empty()) r.set(beast::http::field::sec_websocket_protocol, protocol);
          }));
    }
    ws.handshake(options.host.empty() ? "127.0.0.1:" + std::to_string(port) : options.host, options.path);
    ws.binary(true);
  } catch (const boost::system::system_error& e) {
    throw WsError(e.what());
  }
}

WsClient::~WsClient() = default;

std::string WsClient::Read() {
  beast::flat_buffer b;
  try {
    impl_->ws.read(b);
  } catch (const boost::system::system_error& e) {
    throw WsError(e.what());
  }
  return beast::buffers_to_string(b.data());
}

bool WsClient::TryRead(std::string* message) {
  beast::flat_buffer b;
  beast::error_code ec;
  impl_->ws.read(b, ec);
  if (ec) return false;
  if (message) *message = beast::buffers_to_string(b.data());
  return true;
}

void WsClient::WriteText(const std::string& message) {
  try {
    impl_->ws.text(true);
    impl_->ws.write(asio::buffer(message));
    impl_->ws.binary(true);
  } catch (const boost::system::system_error& e) {
    throw WsError(e.what());
  }
}

void WsClient::Write(const std::string& message) {
  try {
    impl_->ws.write(asio::buffer(message));
  } catch (const boost::system::system_error& e) {
    throw WsError(e.what());
  }
}

bool WsClient::TryWrite(const std::string& message) {
  beast::error_code ec;
  impl_->ws.write(asio::buffer(message), ec);
  return !ec;
}

bool WsClient::SendRaw(const std::string& bytes) {
  beast::error_code ec;
  impl_->ws.next_layer().send(asio::buffer(bytes), 0, ec);
  return !ec;
}

WsCloseReason WsClient::close_reason() const {
  const beast::websocket::close_reason& r = impl_->ws.reason();
  return {static_cast<int>(r.code), std::string(r.reason.c_str())};
}

int WsClient::native_handle() { return impl_->ws.next_layer().native_handle(); }

}  // namespace vlab::view::view_test
