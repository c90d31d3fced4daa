// The view's HTTP sessions (view_server_impl.h): Host and Origin checked,
// a deadline on each request head, answers from the in-memory table, and
// the hand-over of a WebSocket upgrade.
#include <algorithm>
#include <list>
#include <memory>
#include <optional>
#include <string>

#include <boost/beast/websocket.hpp>

#include "view/view_server_impl.h"

namespace vlab::view {

namespace {

using Impl = ViewServer::Impl;

// true when the upgrade's Sec-WebSocket-Protocol lists foxglove.websocket.v1
bool OffersFoxglove(const http::request<http::string_body>& request) {
  const auto range = request.equal_range(http::field::sec_websocket_protocol);
  for (auto at = range.first; at != range.second; ++at) {
    const std::string list(at->value());
    std::size_t start = 0;
    while (start <= list.size()) {
      const std::size_t comma = std::min(list.find(',', start), list.size());
      std::string item = list.substr(start, comma - start);
      item.erase(0, item.find_first_not_of(" \t"));
      item.erase(item.find_last_not_of(" \t") + 1);
      if (item == kFoxgloveSubprotocol) return true;
      start = comma + 1;
    }
  }
  return false;
}

// ---- HTTP: one request after another on a connection
class HttpSession : public std::enable_shared_from_this<HttpSession>, public Impl::Waiting {
 public:
  HttpSession(Impl& server, tcp::socket socket, std::string address) : server_(server), stream_(std::move(socket)) {
    this->address = std::move(address);
  }
  ~HttpSession() {
    Unwait();
    Uncount();
  }

  // admitted: in the tables; otherwise answered 503 and closed
  void Start(bool admitted) {
    if (!admitted) {
      ++server_.refused;
      Reply(http::status::service_unavailable, "", "", false, 11);
      return;
    }
    counted_ = true;
    ++server_.http_open;
    ++server_.http_clients;
    ++server_.peers[address].http;
    Read();
  }
  void Evict() override {
    Unwait();
    Uncount();
    ++server_.evicted;
    stream_.close();  // the pending read ends (operation_aborted), and with it the session
  }

 private:
  void Uncount() {
    if (!counted_) return;
    counted_ = false;
    --server_.http_open;
    --server_.http_clients;
    server_.Release(address, false);
  }
  void Unwait() {
    if (!waiting_) return;
    waiting_ = false;
    server_.waiting.erase(in_waiting_);
  }
  void Read() {
    parser_.emplace();
    parser_->header_limit(static_cast<std::uint32_t>(server_.config.max_header_bytes));
    parser_->body_limit(server_.config.max_body_bytes);
    buffer_.clear();
    in_waiting_ = server_.waiting.insert(server_.waiting.end(), this);
    waiting_ = true;
    stream_.expires_after(Seconds(server_.config.header_timeout_s));  // the whole head (and the small body)
    http::async_read(stream_, buffer_, *parser_,
                     [self = shared_from_this()](beast::error_code ec, std::size_t) { self->OnRead(ec); });
  }

  void OnRead(beast::error_code ec) {
    Unwait();
    if (ec == beast::error::timeout) ++server_.header_timeouts;
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
    // who: a foreign Host (DNS rebinding) or Origin (a page elsewhere) is refused
    if (request.count(http::field::host) > 1 || request.count(http::field::origin) > 1) {
      return Reply(http::status::bad_request, "", "", false, version);
    }
    const auto host = request.find(http::field::host), origin = request.find(http::field::origin);
    if (host != request.end() && !HostAllowed(server_.access, std::string(host->value()))) {
      ++server_.bad_host;
      return Reply(http::status::misdirected_request,
                   "this view answers to localhost, 127.0.0.1, [::1] and its --bind address; start it with "
                   "--allow-host NAME to be opened by another name",
                   "", false, version);
    }
    if (origin != request.end() && !OriginAllowed(server_.access, std::string(origin->value()))) {
      ++server_.bad_host;
      return Reply(http::status::forbidden, "a page of another site may not read this view", "", false, version);
    }
    const std::string target(request.target());
    const std::string path = target.substr(0, target.find('?'));
    if (websocket::is_upgrade(request)) return Upgrade(std::move(request), path);
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

  // a WebSocket: the connection leaves the HTTP table for the WebSocket one
  void Upgrade(http::request<http::string_body> request, const std::string& path) {
    const auto& channels = server_.config.channels;
    const auto channel = std::find(channels.begin(), channels.end(), path);
    if (channel == channels.end()) return Reply(http::status::not_found, "", "", false, request.version());
    const ViewServerConfig& c = server_.config;
    const int from_here = server_.peers.count(address) ? server_.peers[address].ws : 0;
    std::string refusal;
    if (server_.ws_open >= c.max_connections) {
      refusal = "server full: " + std::to_string(c.max_connections) + " sessions open (vlab view --max-connections)";
    } else if (from_here >= c.max_per_address) {
      refusal = "server full: " + std::to_string(c.max_per_address) + " sessions from " + address +
                " (vlab view --max-per-address)";
    }
    if (!refusal.empty()) {
      ++server_.refused;
      // refusals are sessions too, briefly: beyond as many as HTTP connections, a plain 503
      if (server_.refusing >= c.max_http) return Reply(http::status::service_unavailable, "", "", false, 11);
    }
    if (c.foxglove && !OffersFoxglove(request)) {
      return Reply(
          http::status::bad_request,
          std::string("a Foxglove WebSocket server: the client must offer the subprotocol ") + kFoxgloveSubprotocol, "",
          false, request.version());
    }
    ++server_.requests;
    stream_.expires_never();
    Uncount();
    if (c.foxglove) {
      return StartFoxgloveSession(server_, stream_.release_socket(), address, refusal, std::move(request));
    }
    StartWebSocket(server_, stream_.release_socket(), static_cast<int>(channel - channels.begin()), address, refusal,
                   std::move(request));
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
    // an error's body: its status line, and why when there is more to say
    const std::string why = status == http::status::service_unavailable ? "server full" : body;
    response->body() = error ? std::to_string(static_cast<int>(status)) + " " +
                                   std::string(http::obsolete_reason(status)) + (why.empty() ? "" : ": " + why) + "\n"
                             : body;
    response->prepare_payload();
    if (head) response->body().clear();  // Content-Length stays the GET's
    response->keep_alive(keep);
    stream_.expires_after(Seconds(server_.config.response_timeout_s));
    http::async_write(stream_, *response,
                      [self = shared_from_this(), response, keep](beast::error_code ec, std::size_t) {
                        if (ec || !keep) return self->Close();
                        self->Read();
                      });
  }

  void Close() {
    beast::error_code ignored;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
  }

  Impl& server_;
  beast::tcp_stream stream_;
  beast::flat_buffer buffer_{16384};
  std::optional<http::request_parser<http::string_body>> parser_;
  std::list<Impl::Waiting*>::iterator in_waiting_;
  bool waiting_ = false, counted_ = false;
};

}  // namespace

void StartHttpSession(ViewServer::Impl& server, tcp::socket socket, std::string address, bool admitted) {
  std::make_shared<HttpSession>(server, std::move(socket), std::move(address))->Start(admitted);
}

}  // namespace vlab::view
