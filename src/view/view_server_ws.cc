// The view's WebSocket sessions (view_server_impl.h): the newest frame of a
// channel to one client, a one-message send queue with a write deadline,
// pings on silence; and the refusal of a full table as a close reason.
#include <chrono>
#include <memory>
#include <string>

#include <boost/beast/websocket.hpp>

#include "view/view_server_impl.h"

namespace vlab::view {

namespace {

using Impl = ViewServer::Impl;

// ---- WebSocket: the newest frame to one client, what it sends dropped; or,
// when the table is full, a session that only says so and closes
class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(Impl& server, tcp::socket socket, int channel, std::string address, std::string refusal)
      : server_(server), ws_(std::move(socket)), timer_(ws_.get_executor()), channel_(channel),
        seat_(server, std::move(address), std::move(refusal)) {}

  void Start(http::request<http::string_body> request) {
    ApplyWsBounds(ws_, server_.config);
    ws_.binary(true);
    if (!seat_.refusal().empty()) {
      // the browser cannot read an HTTP status of a failed upgrade, only a close's code and reason
      ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) {
        if (ec) return;
        self->ws_.async_close({websocket::close_code::try_again_later, self->seat_.refusal()},
                              [self](beast::error_code) {});
      });
      return;
    }
    ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) {
      if (ec) return;
      self->seat_.Welcome();
      self->Read();
      self->Poll();
    });
  }

 private:
  void Read() {
    ws_.async_read(in_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) return self->End(ec);
      self->in_.consume(self->in_.size());  // read-only: dropped
      self->Read();
    });
  }
  // the first error of the read or of a write ends the session (Beast hands a timeout to
  // whichever of them looks first)
  void End(const beast::error_code& ec) {
    CountWsEnd(server_, ec, done_);
    done_ = true;
    timer_.cancel();
  }
  void Poll() {
    if (done_) return;
    const auto now = std::chrono::steady_clock::now();
    if (writing_ && now - write_start_ > Seconds(server_.config.send_timeout_s)) {
      // the one message of its queue is still not taken: a client that does not read
      ++server_.ws_closed_slow;
      done_ = true;
      beast::get_lowest_layer(ws_).close();
      return;
    }
    if (!writing_) {
      std::uint64_t version = 0;
      std::shared_ptr<const std::string> frame = server_.Newest(channel_, &version);
      if (frame && version != sent_) {
        if (sent_ != 0 && version > sent_ + 1) server_.frames_skipped += static_cast<long>(version - sent_ - 1);
        sent_ = version;
        writing_ = true;
        write_start_ = now;
        ws_.async_write(asio::buffer(*frame), [self = shared_from_this(), frame](beast::error_code ec, std::size_t) {
          self->writing_ = false;
          if (ec) return self->End(ec);
          ++self->server_.frames_sent;
        });
      }
    }
    timer_.expires_after(Seconds(server_.config.frame_poll_s));
    timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (!ec) self->Poll();
    });
  }

  Impl& server_;
  websocket::stream<beast::tcp_stream> ws_;
  asio::steady_timer timer_;
  beast::flat_buffer in_;
  int channel_;
  WsSeat seat_;
  std::uint64_t sent_ = 0;
  std::chrono::steady_clock::time_point write_start_;
  bool writing_ = false, done_ = false;
};

}  // namespace

void StartWebSocket(ViewServer::Impl& server, tcp::socket socket, int channel, std::string address, std::string refusal,
                    http::request<http::string_body> request) {
  std::make_shared<WsSession>(server, std::move(socket), channel, std::move(address), std::move(refusal))
      ->Start(std::move(request));
}

}  // namespace vlab::view
