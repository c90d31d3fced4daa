// The view's Beast server (view_server.h): the listener and its admission
// (view_server_impl.h: the tables), the frame slots, the counters. The
// sessions are in view_server_http.cc and view_server_ws.cc.
#include "view/view_server.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <thread>

#include "core/core_errors.h"
#include "view/view_server_impl.h"

namespace vlab::view {

void ViewServer::Impl::Accept() {
  acceptor->async_accept([this](beast::error_code ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted) return;
    if (ec) {
      // out of descriptors, or the like: try again in a moment, not in a busy loop
      accept_retry->expires_after(std::chrono::milliseconds(50));
      accept_retry->async_wait([this](beast::error_code wait_ec) {
        if (!wait_ec) Accept();
      });
      return;
    }
    beast::error_code endpoint_ec;
    const tcp::endpoint remote = socket.remote_endpoint(endpoint_ec);
    const std::string address = endpoint_ec ? std::string() : remote.address().to_string();
    // full (in all, or from this address): the connection that has waited longest for a request head makes room
    const auto peer = peers.find(address);
    const bool address_full = peer != peers.end() && peer->second.http >= config.max_per_address;
    bool admitted = true;
    if (address_full || http_open >= config.max_http) {
      const auto victim = std::find_if(waiting.begin(), waiting.end(),
                                       [&](const Waiting* w) { return !address_full || w->address == address; });
      if (victim != waiting.end())
        (*victim)->Evict();
      else
        admitted = false;
    }
    StartHttpSession(*this, std::move(socket), address, admitted);
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
  if (config.max_connections < 1 || config.max_http < 1 || config.max_per_address < 1) {
    throw InputError("vlab view: --max-connections and --max-per-address must be >= 1");
  }
  if (config.foxglove) {
    impl->config.channels = {"/"};
    impl->foxglove_info = FoxgloveServerInfo();
    impl->foxglove_advertise = FoxgloveAdvertise(config.foxglove_channels);
  }
  impl->slots.resize(config.foxglove ? config.foxglove_channels.size() : config.channels.size());
  impl->accept_retry = std::make_unique<asio::steady_timer>(*impl->io);
  const std::string where = config.bind + ":" + std::to_string(config.port);
  try {
    const tcp::endpoint endpoint(asio::ip::make_address(config.bind), static_cast<unsigned short>(config.port));
    impl->acceptor->open(endpoint.protocol());
    impl->acceptor->set_option(asio::socket_base::reuse_address(true));
    impl->acceptor->bind(endpoint);
    impl->acceptor->listen(asio::socket_base::max_listen_connections);
    impl->address = impl->acceptor->local_endpoint().address().to_string();
    impl->port = impl->acceptor->local_endpoint().port();
    impl->access = {impl->address, config.allowed_hosts, config.allowed_origins};
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
  impl_->accept_retry.reset();
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
int ViewServer::http_connections() const { return impl_->http_clients.load(); }

ViewServerCounters ViewServer::counters() const {
  const Impl& s = *impl_;
  ViewServerCounters c;
  c.requests = s.requests.load();
  c.errors = s.errors.load();
  c.refused = s.refused.load();
  c.evicted = s.evicted.load();
  c.header_timeouts = s.header_timeouts.load();
  c.bad_host = s.bad_host.load();
  c.ws_sessions = s.ws_sessions.load();
  c.frames_sent = s.frames_sent.load();
  c.frames_skipped = s.frames_skipped.load();
  c.ws_closed_bad = s.ws_closed_bad.load();
  c.ws_closed_slow = s.ws_closed_slow.load();
  c.client_refused = s.client_refused.load();
  c.client_bad = s.client_bad.load();
  return c;
}

}  // namespace vlab::view
