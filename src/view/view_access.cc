// The view's Host and Origin rules (view_access.h).
#include "view/view_access.h"

#include <algorithm>
#include <cctype>

#include <boost/asio/ip/address.hpp>

namespace vlab::view {

namespace {

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

bool Digits(const std::string& s) {
  return !s.empty() && s.size() <= 5 && s.find_first_not_of("0123456789") == std::string::npos;
}

// "name", "name:port", "[v6]", "[v6]:port" -> the name or address without
// brackets and port; false when malformed
bool SplitHost(const std::string& host, std::string* name) {
  if (host.empty()) return false;
  if (host.front() == '[') {
    const std::size_t close = host.find(']');
    if (close == std::string::npos || close < 2) return false;
    const std::string rest = host.substr(close + 1);
    if (!rest.empty() && !(rest.front() == ':' && Digits(rest.substr(1)))) return false;
    *name = host.substr(1, close - 1);
    return name->find(':') != std::string::npos;  // brackets hold an IPv6 address only
  }
  const std::size_t colon = host.find(':');
  if (colon != std::string::npos) {
    if (host.find(':', colon + 1) != std::string::npos || !Digits(host.substr(colon + 1))) return false;
    *name = host.substr(0, colon);
  } else {
    *name = host;
  }
  if (!name->empty() && name->back() == '.') name->pop_back();  // "localhost." is localhost
  return !name->empty();
}

bool NameAllowed(const AccessPolicy& policy, const std::string& raw) {
  const std::string name = Lower(raw);
  if (name == "localhost") return true;
  for (const std::string& allowed : policy.allowed_hosts) {
    std::string a = Lower(allowed);
    if (!a.empty() && a.back() == '.') a.pop_back();
    if (a.size() > 2 && a.front() == '[' && a.back() == ']') a = a.substr(1, a.size() - 2);
    if (a == name) return true;
  }
  boost::system::error_code ec;
  const boost::asio::ip::address address = boost::asio::ip::make_address(name, ec);
  if (ec) return false;  // a name nobody allowed: a rebinding page's, or a typo
  if (IsLoopbackAddress(name)) return true;
  boost::system::error_code bound_ec;
  const boost::asio::ip::address bound = boost::asio::ip::make_address(policy.bound, bound_ec);
  if (bound_ec) return false;
  return address == bound || bound.is_unspecified();
}

}  // namespace

bool IsLoopbackAddress(const std::string& text) {
  boost::system::error_code ec;
  const boost::asio::ip::address a = boost::asio::ip::make_address(text, ec);
  if (ec) return false;
  if (a.is_v6() && a.to_v6().is_v4_mapped()) {
    return boost::asio::ip::make_address_v4(boost::asio::ip::v4_mapped, a.to_v6()).is_loopback();
  }
  return a.is_loopback();
}

bool ValidOrigin(const std::string& origin) {
  const std::string o = Lower(origin);
  std::string rest;
  if (o.compare(0, 7, "http://") == 0)
    rest = o.substr(7);
  else if (o.compare(0, 8, "https://") == 0)
    rest = o.substr(8);
  else
    return false;
  std::string name;
  return rest.find_first_of("/?#@ ") == std::string::npos && SplitHost(rest, &name);
}

bool HostAllowed(const AccessPolicy& policy, const std::string& host) {
  std::string name;
  return SplitHost(host, &name) && NameAllowed(policy, name);
}

bool OriginAllowed(const AccessPolicy& policy, const std::string& origin) {
  const std::string o = Lower(origin);
  for (const std::string& allowed : policy.allowed_origins) {
    if (!allowed.empty() && Lower(allowed) == o) return true;  // the whole origin, scheme and port included
  }
  std::string rest;
  if (o.compare(0, 7, "http://") == 0)
    rest = o.substr(7);
  else if (o.compare(0, 8, "https://") == 0)
    rest = o.substr(8);
  else
    return false;  // "null" (a sandboxed frame, a file:// page) and any other scheme
  if (rest.find_first_of("/?#@") != std::string::npos) return false;
  return HostAllowed(policy, rest);
}

std::string UrlHost(const std::string& address) {
  return address.find(':') != std::string::npos ? "[" + address + "]" : address;
}

}  // namespace vlab::view
