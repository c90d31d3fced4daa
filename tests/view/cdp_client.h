// A headless Chromium driven over the Chrome DevTools Protocol, for the
// browser tests of vlab view: start it, open a page, evaluate JavaScript,
// take PNG screenshots. Chromium is found as $VLAB_CHROMIUM or `chromium` on
// the PATH; when there is none, the constructor throws with what to install
// (the test fails: it must not pass silently where the browser is missing).
// The DevTools connection lives in cdp_client.cc (library
// vlab_view_test_clients), so that a test unit does not parse Boost.
#pragma once

#include <memory>
#include <string>

#include <nlohmann/json.hpp>

namespace vlab::testing {

class Chromium {
 public:
  /// Starts headless Chromium (SwiftShader WebGL, window width x height pixels)
  /// with its profile in `profile_dir`, and attaches to its first page. Throws
  /// std::runtime_error when it is missing or does not start within 30 s; a
  /// browser that was started is killed again then.
  Chromium(const std::string& profile_dir, int width, int height);
  /// Kills the browser (its whole process group) and reaps it.
  ~Chromium();
  Chromium(const Chromium&) = delete;
  Chromium& operator=(const Chromium&) = delete;

  /// A DevTools command; returns its "result", skipping the events that come
  /// before it. Throws std::runtime_error on an "error" reply (message:
  /// method and error), and the socket's error when the connection fails.
  nlohmann::json Call(const std::string& method, const nlohmann::json& params = nlohmann::json::object());
  /// The value of a JavaScript expression (a promise is awaited). Throws
  /// std::runtime_error "javascript: ..." when the expression throws.
  nlohmann::json Evaluate(const std::string& expression);
  /// The page as PNG bytes.
  std::string Screenshot();

  /// The browser's executable: $VLAB_CHROMIUM, or chromium / chromium-browser
  /// on the PATH. Throws std::runtime_error naming the package when none is.
  static std::string Find();

 private:
  struct Impl;  // the process and its DevTools WebSocket (cdp_client.cc)
  std::unique_ptr<Impl> impl_;
};

}  // namespace vlab::testing
