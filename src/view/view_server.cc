// The view's Beast server (view_server.h): a listener, HTTP sessions that
// answer from the in-memory table, and WebSocket sessions fed by a poll timer.
#include "view/view_server.h"

#include <algorithm>
#include <chrono>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "core/core_errors.h"

namespace vlab::view {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

struct ViewServer::Impl {
  ViewServerConfig config;
  std::map<std::string, StaticFile> files;
  Resources resources;
  // both destroyed first, by ~ViewServer: pending handlers own sessions that use the rest
  std::unique_ptr<asio::io_context> io = std::make_unique<asio::io_context>(1);
  std::unique_ptr<tcp::acceptor> acceptor = std::make_unique<tcp::acceptor>(*io);
  std::thread thread;
  std::string address;
  int port = 0;

  // per channel, the newest message, swapped under the lock; version counts messages published
  struct Slot {
    std::shared_ptr<const std::string> frame;
    std::uint64_t version = 0;
  };
  mutable std::mutex frame_mutex;
  std::vector<Slot> slots;

  std::atomic<int> connections{0}, ws_clients{0};
  std::atomic<long> requests{0}, errors{0}, refused{0}, ws_sessions{0}, frames_sent{0}, frames_skipped{0},
      ws_closed_bad{0};

  std::shared_ptr<const std::string> Newest(int channel, std::uint64_t* v) const {
    std::lock_guard<std::mutex> lock(frame_mutex);
    *v = slots[channel].version;
    return slots[channel].frame;
  }
  void Accept();
};

namespace {

using Impl = ViewServer::Impl;

// counts a connection for as long as its session lives
struct ConnectionSlot {
  explicit ConnectionSlot(Impl& s) : server(s) { ++server.connections; }
  ~ConnectionSlot() { --server.connections; }
  Impl& server;
};

// ---- WebSocket: the newest frame to one client, what it sends dropped
class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(Impl& server, tcp::socket socket, int channel)
      : server_(server), slot_(server), ws_(std::move(socket)), timer_(ws_.get_executor()), channel_(channel) {}

  void Start(http::request<http::string_body> request) {
    ws_.read_message_max(server_.config.max_ws_message_bytes);
    ws_.binary(true);
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) {
      if (ec) return;
      ++self->server_.ws_sessions;
      ++self->server_.ws_clients;
      self->counted_ = true;
      self->Read();
      self->Poll();
    });
  }
  ~WsSession() {
    if (counted_) --server_.ws_clients;
  }

 private:
  void Read() {
    ws_.async_read(in_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) {
        // a protocol violation or an oversized message (not a close, a reset or a timeout)
        const bool websocket_error = ec.category() == websocket::make_error_code(websocket::error::closed).category();
        if (websocket_error && ec != websocket::error::closed) ++self->server_.ws_closed_bad;
        self->done_ = true;
        self->timer_.cancel();
        return;
      }
      self->in_.consume(self->in_.size());  // read-only: dropped
      self->Read();
    });
  }
  void Poll() {
    if (done_) return;
    if (!writing_) {
      std::uint64_t version = 0;
      std::shared_ptr<const std::string> frame = server_.Newest(channel_, &version);
      if (frame && version != sent_) {
        if (sent_ != 0 && version > sent_ + 1) server_.frames_skipped += static_cast<long>(version - sent_ - 1);
        sent_ = version;
        writing_ = true;
        ws_.async_write(asio::buffer(*frame), [self = shared_from_this(), frame](beast::error_code ec, std::size_t) {
          self->writing_ = false;
          if (ec) {
            self->done_ = true;
            self->timer_.cancel();
            return;
          }
          ++self->server_.frames_sent;
        });
      }
    }
    timer_.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(server_.config.frame_poll_s)));
    timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (!ec) self->Poll();
    });
  }

  Impl& server_;
  ConnectionSlot slot_;
  websocket::stream<beast::tcp_stream> ws_;
  asio::steady_timer timer_;
  beast::flat_buffer in_;
  int channel_;
  std::uint64_t sent_ = 0;
  bool writing_ = false, done_ = false, counted_ = false;
};

// ---- HTTP: one request after another on a connection
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(Impl& server, tcp::socket socket, bool too_many)
      : server_(server), slot_(server), stream_(std::move(socket)), too_many_(too_many) {}

  void Start() {
    if (too_many_) {
      ++server_.refused;
      Reply(http::status::service_unavailable, "too many connections\n", "text/plain", false, 11);
      return;
    }
    Read();
  }

 private:
  void Read() {
    parser_.emplace();
    parser_->header_limit(static_cast<std::uint32_t>(server_.config.max_header_bytes));
    parser_->body_limit(server_.config.max_body_bytes);
    buffer_.clear();
    stream_.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(server_.config.idle_timeout_s)));
    http::async_read(stream_, buffer_, *parser_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      self->OnRead(ec);
    });
  }

  void OnRead(beast::error_code ec) {
    if (ec == http::error::end_of_stream || ec == beast::error::timeout || ec == asio::error::operation_aborted ||
        ec == asio::error::connection_reset || ec == asio::error::eof) {
      Close();
      return;
    }
    if (ec == http::error::header_limit) return Reply(http::status::request_header_fields_too_large, "", "", false, 11);
    if (ec == http::error::body_limit) return Reply(http::status::payload_too_large, "", "", false, 11);
    if (ec) return Reply(http::status::bad_request, "", "", false, 11);
    http::request<http::string_body> request = parser_->release();
    const unsigned version = request.version();
    const std::string target(request.target());
    const std::string path = target.substr(0, target.find('?'));
    if (websocket::is_upgrade(request)) {
      const auto& channels = server_.config.channels;
      const auto channel = std::find(channels.begin(), channels.end(), path);
      if (channel == channels.end()) return Reply(http::status::not_found, "", "", false, version);
      ++server_.requests;
      stream_.expires_never();
      std::make_shared<WsSession>(server_, stream_.release_socket(), static_cast<int>(channel - channels.begin()))
          ->Start(std::move(request));
      return;
    }
    const bool keep = request.keep_alive();
    if (request.method() != http::verb::get && request.method() != http::verb::head) {
      return Reply(http::status::method_not_allowed, "", "", keep, version);
    }
    const bool head = request.method() == http::verb::head;
    const std::string key = path == "/" ? "/index.html" : path;
    auto file = server_.files.find(key);
    if (file != server_.files.end()) {
      return Reply(http::status::ok, file->second.body, file->second.content_type, keep, version, head);
    }
    std::string type, body;
    if (path.size() < 256 && server_.resources && server_.resources(path, &type, &body)) {
      return Reply(http::status::ok, body, type, keep, version, head);
    }
    Reply(http::status::not_found, "", "", keep, version);
  }

  void Reply(http::status status, const std::string& body, const std::string& type, bool keep, unsigned version,
             bool head = false) {
    ++server_.requests;
    const bool error = static_cast<int>(status) >= 400;
    if (error) ++server_.errors;
    auto response = std::make_shared<http::response<http::string_body>>(status, version);
    response->set(http::field::server, "vlab view");
    response->set(http::field::content_type, error ? "text/plain" : type);
    response->set(http::field::cache_control, "no-store");
    response->set("X-Content-Type-Options", "nosniff");
    response->body() = error ? std::to_string(static_cast<int>(status)) + " " + std::string(http::obsolete_reason(status)) + "\n"
                             : body;
    response->prepare_payload();
    if (head) response->body().clear();  // Content-Length stays the GET's
    response->keep_alive(keep);
    http::async_write(stream_, *response, [self = shared_from_this(), response, keep](beast::error_code ec, std::size_t) {
      if (ec || !keep) return self->Close();
      self->Read();
    });
  }

  void Close() {
    beast::error_code ignored;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
  }

  Impl& server_;
  ConnectionSlot slot_;
  beast::tcp_stream stream_;
  bool too_many_;
  beast::flat_buffer buffer_{16384};
  std::optional<http::request_parser<http::string_body>> parser_;
};

}  // namespace

void ViewServer::Impl::Accept() {
  acceptor->async_accept([this](beast::error_code ec, tcp::socket socket) {
    if (ec) {
      if (ec == asio::error::operation_aborted) return;
    } else {
      const bool too_many = connections.load() >= config.max_connections;
      std::make_shared<HttpSession>(*this, std::move(socket), too_many)->Start();
    }
    Accept();
  });
}

std::unique_ptr<ViewServer> ViewServer::Create(const ViewServerConfig& config, std::map<std::string, StaticFile> files,
                                               Resources resources) {
  auto impl = std::make_unique<Impl>();
  impl->config = config;
  impl->files = std::move(files);
  impl->resources = std::move(resources);
  if (config.channels.empty()) throw InputError("vlab view: a server needs at least one WebSocket channel");
  impl->slots.resize(config.channels.size());
  const std::string where = config.bind + ":" + std::to_string(config.port);
  try {
    const tcp::endpoint endpoint(asio::ip::make_address(config.bind), static_cast<unsigned short>(config.port));
    impl->acceptor->open(endpoint.protocol());
    impl->acceptor->set_option(asio::socket_base::reuse_address(true));
    impl->acceptor->bind(endpoint);
    impl->acceptor->listen(asio::socket_base::max_listen_connections);
    impl->address = impl->acceptor->local_endpoint().address().to_string();
    impl->port = impl->acceptor->local_endpoint().port();
  } catch (const std::exception& e) {
    throw InputError("vlab view: cannot serve HTTP on " + where + ": " + e.what());
  }
  impl->Accept();
  Impl* raw = impl.get();
  impl->thread = std::thread([raw] { raw->io->run(); });
  return std::unique_ptr<ViewServer>(new ViewServer(std::move(impl)));
}

ViewServer::ViewServer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

ViewServer::~ViewServer() {
  impl_->io->stop();
  if (impl_->thread.joinable()) impl_->thread.join();
  impl_->acceptor.reset();
  impl_->io.reset();
}

void ViewServer::Publish(std::string frame, int channel) {
  if (channel < 0 || channel >= static_cast<int>(impl_->slots.size())) {
    throw std::invalid_argument("vlab view: no WebSocket channel " + std::to_string(channel));
  }
  auto shared = std::make_shared<const std::string>(std::move(frame));
  std::lock_guard<std::mutex> lock(impl_->frame_mutex);
  impl_->slots[channel].frame = std::move(shared);
  ++impl_->slots[channel].version;
}

int ViewServer::port() const { return impl_->port; }
const std::string& ViewServer::address() const { return impl_->address; }
int ViewServer::clients() const { return impl_->ws_clients.load(); }

ViewServerCounters ViewServer::counters() const {
  const Impl& s = *impl_;
  return {s.requests.load(),     s.errors.load(),       s.refused.load(),      s.ws_sessions.load(),
          s.frames_sent.load(),  s.frames_skipped.load(), s.ws_closed_bad.load()};
}

}  // namespace vlab::view
