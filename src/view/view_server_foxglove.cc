// A Foxglove server's WebSocket sessions (view_server_impl.h, view_foxglove.h):
// serverInfo and advertise first, then the newest message of each subscribed
// channel, one write at a time; what the client sends is applied to its
// subscriptions or refused with a status message (read-only).
#include <chrono>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include <boost/beast/websocket.hpp>

#include "view/view_server_impl.h"

namespace vlab::view {

namespace {

using Impl = ViewServer::Impl;

// status messages waiting to be sent at most; more are dropped (a client that
// floods refused requests gets no more answers than it reads)
constexpr std::size_t kMaxQueuedText = 8;

class FoxgloveSession : public std::enable_shared_from_this<FoxgloveSession> {
 public:
  FoxgloveSession(Impl& server, tcp::socket socket, std::string address, std::string refusal)
      : server_(server), ws_(std::move(socket)), timer_(ws_.get_executor()),
        seat_(server, std::move(address), std::move(refusal)), subscriptions_(static_cast<int>(server.slots.size())),
        sent_(server.slots.size(), 0) {}

  void Start(http::request<http::string_body> request) {
    ApplyWsBounds(ws_, server_.config);
    ws_.set_option(websocket::stream_base::decorator([](websocket::response_type& response) {
      response.set(http::field::sec_websocket_protocol, kFoxgloveSubprotocol);
      response.set(http::field::server, "vlab view");
    }));
    if (!seat_.refusal().empty()) {
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
      self->text_.push_back(self->server_.foxglove_info);
      self->text_.push_back(self->server_.foxglove_advertise);
      self->Read();
      self->Poll();
    });
  }

 private:
  void Read() {
    ws_.async_read(in_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) return self->End(ec);
      self->OnMessage(beast::buffers_to_string(self->in_.data()), !self->ws_.got_text());
      self->in_.consume(self->in_.size());
      self->Read();
    });
  }

  // a subscribe or unsubscribe is applied; anything else is answered with an error status
  void OnMessage(const std::string& message, bool binary) {
    bool read_only = false, malformed = false;
    std::vector<std::int64_t> before(sent_.size());
    for (std::size_t c = 0; c < sent_.size(); ++c) before[c] = subscriptions_.IdOf(static_cast<int>(c));
    const std::string why = subscriptions_.Apply(message, binary, &read_only, &malformed);
    // a new subscription starts with the channel's newest message (a scene sent once included)
    for (std::size_t c = 0; c < sent_.size(); ++c) {
      if (subscriptions_.IdOf(static_cast<int>(c)) != before[c]) sent_[c] = 0;
    }
    if (why.empty()) return;
    if (read_only) ++server_.client_refused;
    if (malformed) ++server_.client_bad;
    if (text_.size() < kMaxQueuedText) text_.push_back(FoxgloveStatus(2, why));
  }

  void Poll() {
    if (done_) return;
    const auto now = std::chrono::steady_clock::now();
    if (writing_ && now - write_start_ > Seconds(server_.config.send_timeout_s)) {
      ++server_.ws_closed_slow;
      done_ = true;
      beast::get_lowest_layer(ws_).close();
      return;
    }
    if (!writing_) {
      if (!text_.empty()) {
        WriteText();
      } else {
        WriteNewest(now);
      }
    }
    timer_.expires_after(Seconds(server_.config.frame_poll_s));
    timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (!ec) self->Poll();
    });
  }

  void WriteText() {
    auto message = std::make_shared<std::string>(std::move(text_.front()));
    text_.pop_front();
    writing_ = true;
    write_start_ = std::chrono::steady_clock::now();
    ws_.text(true);
    ws_.async_write(asio::buffer(*message), [self = shared_from_this(), message](beast::error_code ec, std::size_t) {
      self->writing_ = false;
      if (ec) self->End(ec);
    });
  }

  // the next subscribed channel after the last one written that has a message newer than
  // the one it last sent (round robin: a busy channel does not starve the others)
  void WriteNewest(std::chrono::steady_clock::time_point now) {
    const int n = subscriptions_.channels();
    for (int k = 1; k <= n; ++k) {
      const int channel = (next_ + k) % n;
      const std::int64_t id = subscriptions_.IdOf(channel);
      if (id < 0) continue;
      std::uint64_t version = 0;
      std::shared_ptr<const std::string> record = server_.Newest(channel, &version);
      if (!record || version == sent_[channel]) continue;
      if (sent_[channel] != 0 && version > sent_[channel] + 1) {
        server_.frames_skipped += static_cast<long>(version - sent_[channel] - 1);
      }
      sent_[channel] = version;
      next_ = channel;
      FoxgloveDataHeader(static_cast<std::uint32_t>(id), header_);
      writing_ = true;
      write_start_ = now;
      ws_.binary(true);
      const std::vector<asio::const_buffer> buffers = {asio::buffer(header_, sizeof(header_)), asio::buffer(*record)};
      ws_.async_write(buffers, [self = shared_from_this(), record](beast::error_code ec, std::size_t) {
        self->writing_ = false;
        if (ec) return self->End(ec);
        ++self->server_.frames_sent;
      });
      return;
    }
  }

  // the first error of the read or of a write ends the session (Beast hands a timeout to
  // whichever of them looks first)
  void End(const beast::error_code& ec) {
    CountWsEnd(server_, ec, done_);
    done_ = true;
    timer_.cancel();
  }

  Impl& server_;
  websocket::stream<beast::tcp_stream> ws_;
  asio::steady_timer timer_;
  beast::flat_buffer in_;
  WsSeat seat_;
  FoxgloveSubscriptions subscriptions_;
  std::vector<std::uint64_t> sent_;  // per channel, the version last sent (0: none)
  std::deque<std::string> text_;     // JSON messages waiting, sent before any data
  char header_[5] = {};
  int next_ = -1;
  std::chrono::steady_clock::time_point write_start_;
  bool writing_ = false, done_ = false;
};

}  // namespace

void StartFoxgloveSession(ViewServer::Impl& server, tcp::socket socket, std::string address, std::string refusal,
                          http::request<http::string_body> request) {
  std::make_shared<FoxgloveSession>(server, std::move(socket), std::move(address), std::move(refusal))
      ->Start(std::move(request));
}

}  // namespace vlab::view
