// Checks the numbers docs/protocol.md and its sibling pages (protocol_camera.md,
// protocol_markers.md) state against the code's constants: the protocol
// version (title, header tables, JSON examples, the Python example), the kind
// range of a describe request and the kind names a describe reply carries,
// the session reply results, the lockstep timeouts, the subscriber table's
// size, the owner and subscriber timeouts, the watchdog, the seq window, the
// first seq of an arm payload and the largest datagram. Each number is found
// by the sentence that states it; a sentence that is gone is reported, and so
// is every mistake: each check is also run on a copy of the page with its
// number changed, and must fail.
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "bridge/bridge_endpoint.h"
#include "bridge/bridge_protocol.h"
#include "bridge/bridge_session.h"
#include "core/core_clock.h"

namespace vlab::bridge::protocol_doc_numbers_test {
namespace {

std::string ReadPage(const std::string& page) {
  std::ifstream in(std::string(VLAB_SOURCE_DIR) + "/docs/" + page);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// A number a page states: the first group of `pattern` in every place it matches.
struct Stated {
  const char* page;
  const char* what;
  const char* pattern;
  double code;  // the code's value
};

std::vector<Stated> Numbers() {
  const EndpointConfig endpoint;
  const LockstepConfig lockstep;
  const double version = kProtocolVersion;
  return {
      {"protocol.md", "the title's version", R"(# The vlab wire protocol, version (\d+))", version},
      {"protocol.md", "the header's version", R"(\| 1 \| 8 \| version \| (\d+) \|)", version},
      {"protocol_camera.md", "the chunk header's version", R"(\| 1 \| 8 \| version \| (\d+) \|)", version},
      {"protocol_markers.md", "the example's version", R"(\| 1 \| version \| (\d+) \|)", version},
      {"protocol.md", "a JSON example's protocol", R"re("protocol": (\d+))re", version},
      {"protocol_camera.md", "a JSON example's protocol", R"re("protocol": (\d+))re", version},
      {"protocol.md", "the describe reply's protocol", R"(`protocol` \((\d+),)", version},
      {"protocol.md", "the Python example's VERSION", R"(MAGIC, VERSION, ARM = 1447838018, (\d+),)", version},
      {"protocol.md", "the kinds a describe request names", R"(whatever kind it names \(0 to (\d+);)",
       static_cast<double>(kMaxDeviceKind)},
      {"protocol.md", "the highest session result", R"((\d+) payload refused: not the owner)",
       static_cast<double>(kMaxSessionResult)},
      {"protocol.md", "the lockstep timeout per period", R"(per period \((\d+(?:\.\d+)?) s by default)",
       lockstep.timeout_s},
      {"protocol.md", "the per-period timeout of the sim section", R"(per-period timeout, (\d+(?:\.\d+)?) s by)",
       lockstep.timeout_s},
      {"protocol.md", "the start timeout", R"(`start_timeout`, (\d+) s by default)", lockstep.start_timeout_s},
      {"protocol.md", "the subscriber table", R"(subscribers: (\d+) by default)",
       static_cast<double>(kDefaultMaxSubscribers)},
      {"protocol.md", "the owner timeout", R"(`owner_timeout_s`\s+in the describe reply; (\d+(?:\.\d+)?) s by default)",
       endpoint.owner_timeout_s},
      {"protocol.md", "the subscriber timeout", R"(subscriber timeout \((\d+) s of the wall clock\))",
       endpoint.subscriber_timeout_s},
      {"protocol.md", "the watchdog", R"(consecutive\s+periods \((\d+) by default)",
       static_cast<double>(endpoint.watchdog_periods)},
      {"protocol.md", "the seq window", R"(\*\*newest (\d+) states it)", static_cast<double>(kSeqWindow + 1)},
      {"protocol.md", "the first payload seq", R"(\*\*payload counter\*\*: (\d+) for its first payload)",
       kFirstPayloadSeq},
      {"protocol.md", "the first payload seq of a new owner", R"(payloads count from its own (\d+)\.)",
       kFirstPayloadSeq},
      {"protocol.md", "the largest datagram", R"(at most (\d+) values \()", static_cast<double>(kMaxPacketValues)},
  };
}

// what is wrong with the number `s` states in `text` ("" when nothing)
std::string Check(const Stated& s, const std::string& text) {
  const std::regex pattern(s.pattern);
  int found = 0;
  std::string problems;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), pattern); it != std::sregex_iterator(); ++it) {
    ++found;
    if (std::stod((*it)[1]) != s.code) {
      problems += std::string(s.page) + ": " + s.what + " is " + (*it)[1].str() + ", the code's is " +
                  std::to_string(s.code) + "\n";
    }
  }
  if (found == 0) problems += std::string(s.page) + ": " + s.what + ": the sentence is gone (" + s.pattern + ")\n";
  return problems;
}

TEST(ProtocolDocNumbers, EveryNumberThePagesStateIsTheCodes) {
  for (const Stated& s : Numbers()) {
    const std::string text = ReadPage(s.page);
    ASSERT_FALSE(text.empty()) << "cannot read docs/" << s.page;
    EXPECT_EQ(Check(s, text), "");
  }
}

TEST(ProtocolDocNumbers, AChangedNumberIsReported) {
  for (const Stated& s : Numbers()) {
    std::string text = ReadPage(s.page);
    std::smatch m;
    ASSERT_TRUE(std::regex_search(text, m, std::regex(s.pattern))) << s.what;
    text.replace(static_cast<std::size_t>(m.position(1)), static_cast<std::size_t>(m.length(1)),
                 std::to_string(static_cast<long>(s.code) + 7));
    EXPECT_NE(Check(s, text).find(s.what), std::string::npos) << s.what << ": a wrong number not reported";
  }
}

TEST(ProtocolDocNumbers, TheDescribeReplyListsEveryKindName) {
  const std::string text = ReadPage("protocol.md");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(text, m, std::regex(R"(Every reply has `name`, `kind` \(((?:[^()]|\([^()]*\))*)\))")));
  std::vector<std::string> names;
  const std::string list = m[1];
  const std::regex quoted("\"(\\w+)\"");
  for (auto it = std::sregex_iterator(list.begin(), list.end(), quoted); it != std::sregex_iterator(); ++it) {
    names.push_back((*it)[1]);
  }
  std::vector<std::string> code;
  for (int kind = 1; kind <= kMaxDeviceKind; ++kind) code.push_back(KindName(kind));
  EXPECT_EQ(names, code);
}

TEST(ProtocolDocNumbers, TheSessionResultsAreListedInOrder) {
  const std::string text = ReadPage("protocol.md");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(text, m, std::regex(R"(\| 1 \| result \| ([^|]*) \|)")));
  const std::string cell = m[1];
  std::vector<int> listed;
  const std::regex item(R"((?:^|; )(\d+) )");
  for (auto it = std::sregex_iterator(cell.begin(), cell.end(), item); it != std::sregex_iterator(); ++it) {
    listed.push_back(std::stoi((*it)[1]));
  }
  std::vector<int> code;
  for (int r = 0; r <= kMaxSessionResult; ++r) code.push_back(r);
  EXPECT_EQ(listed, code);
}

}  // namespace
}  // namespace vlab::bridge::protocol_doc_numbers_test
