// The DevTools client of cdp_client.h: Chromium as a child process in its own
// process group, its page's WebSocket (Boost.Beast), and the HTTP request that
// finds that WebSocket.
#include "cdp_client.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <stdexcept>
#include <thread>
#include <vector>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

namespace vlab::testing {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;

// the body of GET target on 127.0.0.1:port (HTTP/1.1)
std::string HttpGet(int port, const std::string& target) {
  namespace http = beast::http;
  asio::io_context io;
  beast::tcp_stream stream(io);
  stream.connect({asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)});
  http::request<http::empty_body> request(http::verb::get, target, 11);
  request.set(http::field::host, "127.0.0.1");
  http::write(stream, request);
  beast::flat_buffer b;
  http::response<http::string_body> response;
  http::read(stream, b, response);
  return response.body();
}

// standard base64 to bytes; characters outside the alphabet (padding) are skipped
std::string Base64Decode(const std::string& in) {
  std::string out;
  int bits = 0, value = 0;
  for (const char c : in) {
    int v = -1;
    if (c >= 'A' && c <= 'Z')
      v = c - 'A';
    else if (c >= 'a' && c <= 'z')
      v = c - 'a' + 26;
    else if (c >= '0' && c <= '9')
      v = c - '0' + 52;
    else if (c == '+')
      v = 62;
    else if (c == '/')
      v = 63;
    if (v < 0) continue;
    value = (value << 6) | v;
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<char>((value >> bits) & 0xff));
    }
  }
  return out;
}

}  // namespace

struct Chromium::Impl {
  ~Impl() {
    if (pid > 0) {
      ::kill(-pid, SIGKILL);
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
  }
  asio::io_context io;
  beast::websocket::stream<asio::ip::tcp::socket> ws{io};
  pid_t pid = -1;
  int id = 0;
};

Chromium::Chromium(const std::string& profile_dir, int width, int height) : impl_(std::make_unique<Impl>()) {
  const std::string exe = Find();
  const std::string size = "--window-size=" + std::to_string(width) + "," + std::to_string(height);
  std::vector<std::string> args = {exe,
                                   "--headless",
                                   "--no-sandbox",
                                   "--disable-dev-shm-usage",
                                   "--enable-unsafe-swiftshader",
                                   "--use-angle=swiftshader",
                                   "--disable-gpu-vsync",
                                   "--hide-scrollbars",
                                   "--no-first-run",
                                   "--remote-debugging-port=0",
                                   "--user-data-dir=" + profile_dir,
                                   size,
                                   "about:blank"};
  impl_->pid = ::fork();
  if (impl_->pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, STDOUT_FILENO);
    ::dup2(null, STDERR_FILENO);
    ::setpgid(0, 0);
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  // its DevTools port, then its page's WebSocket
  const std::string port_file = profile_dir + "/DevToolsActivePort";
  int port = 0;
  for (int i = 0; i < 300 && port == 0; ++i) {
    std::ifstream in(port_file);
    if (!(in >> port)) {
      port = 0;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
  if (port == 0) throw std::runtime_error("chromium (" + exe + ") did not start within 30 s");
  const nlohmann::json targets = nlohmann::json::parse(HttpGet(port, "/json/list"));
  std::string url;
  for (const auto& t : targets) {
    if (t.value("type", "") == "page") url = t.value("webSocketDebuggerUrl", "");
  }
  if (url.empty()) throw std::runtime_error("chromium: no page target in /json/list");
  const std::string path = url.substr(url.find('/', std::string("ws://").size()));
  impl_->ws.next_layer().connect({asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)});
  impl_->ws.read_message_max(64 << 20);
  impl_->ws.handshake("127.0.0.1:" + std::to_string(port), path);
}

Chromium::~Chromium() = default;

nlohmann::json Chromium::Call(const std::string& method, const nlohmann::json& params) {
  const int id = ++impl_->id;
  impl_->ws.write(asio::buffer(nlohmann::json{{"id", id}, {"method", method}, {"params", params}}.dump()));
  for (;;) {
    beast::flat_buffer b;
    impl_->ws.read(b);
    const nlohmann::json reply = nlohmann::json::parse(beast::buffers_to_string(b.data()));
    if (reply.value("id", -1) != id) continue;  // an event
    if (reply.contains("error")) throw std::runtime_error(method + ": " + reply["error"].dump());
    return reply["result"];
  }
}

nlohmann::json Chromium::Evaluate(const std::string& expression) {
  const nlohmann::json r =
      Call("Runtime.evaluate", {{"expression", expression}, {"returnByValue", true}, {"awaitPromise", true}});
  if (r.contains("exceptionDetails")) throw std::runtime_error("javascript: " + r["exceptionDetails"].dump());
  return r["result"].value("value", nlohmann::json());
}

std::string Chromium::Screenshot() {
  return Base64Decode(Call("Page.captureScreenshot", {{"format", "png"}})["data"].get<std::string>());
}

std::string Chromium::Find() {
  if (const char* env = std::getenv("VLAB_CHROMIUM"); env && *env) return env;
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/bin";
  for (std::size_t start = 0; start <= dirs.size();) {
    const std::size_t end = dirs.find(':', start);
    const std::string dir = dirs.substr(start, end == std::string::npos ? std::string::npos : end - start);
    for (const char* name : {"chromium", "chromium-browser"}) {
      const std::string candidate = dir + "/" + name;
      if (::access(candidate.c_str(), X_OK) == 0) return candidate;
    }
    if (end == std::string::npos) break;
    start = end + 1;
  }
  throw std::runtime_error(
      "no chromium on the PATH (nor $VLAB_CHROMIUM): the browser test needs Debian's chromium, one of "
      "tools/setup.sh's VLAB_TEST_APT_PACKAGES (apt-get install chromium)");
}

}  // namespace vlab::testing
