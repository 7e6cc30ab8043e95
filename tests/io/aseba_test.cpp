// The Aseba link (io/aseba_*): messages round-trip through the decoder whole and in pieces; what
// is malformed or hostile (an oversized length, half a word, a description that claims memory the
// node does not have, a reply outside it) is refused and counted while good traffic goes on; and
// a host finds, describes, reads, writes and exchanges events with a node over TCP.
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "symb/io/aseba_link.hpp"
#include "symb/io/tcp_stream.hpp"

#include "support/aseba_node.hpp"
#include "support/eventually.hpp"

namespace symb::io::aseba {
namespace {

using namespace std::chrono_literals;
using Bytes = std::vector<std::byte>;

// How long a peer that is there is given to answer: a call returns as soon as the answer comes, and
// on a busy box the peer's thread may be kept off its core for seconds.
constexpr auto kAnswer = symb::testing::kEventuallyLimit;

std::vector<Message> decode_all(std::span<const std::byte> in, AsebaDecoder& d) {
  std::vector<Message> out;
  d.feed(in, [&](const Message& m) { out.push_back(m); });
  return out;
}

Bytes cat(std::initializer_list<Bytes> parts) {
  Bytes out;
  for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

TEST(AsebaMessage, RequestsRoundTripWholeAndByteByByte) {
  const std::int16_t values[3] = {-1, 0, 500};
  const Bytes wire = cat({list_nodes(), get_node_description(7), get_variables(7, 42, 7), *set_variables(7, 57, values),
                          *user_event(3, values)});
  AsebaDecoder whole;
  const auto a = decode_all(wire, whole);
  AsebaDecoder bytewise;
  std::vector<Message> b;
  for (std::byte x : wire) {
    auto got = decode_all(std::span<const std::byte>(&x, 1), bytewise);
    b.insert(b.end(), got.begin(), got.end());
  }
  ASSERT_EQ(a.size(), 5u);
  ASSERT_EQ(b.size(), 5u);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].type, b[i].type);
    EXPECT_EQ(a[i].payload, b[i].payload);
    EXPECT_EQ(a[i].source, kHostId);
  }
  EXPECT_EQ(a[0].type, type::kListNodes);
  EXPECT_EQ(*AsebaReader(a[0].payload).word(), kProtocolVersion);
  AsebaReader get(a[2].payload);
  EXPECT_EQ(*get.word(), 7);
  EXPECT_EQ(*get.word(), 42);
  EXPECT_EQ(*get.word(), 7);
  EXPECT_EQ(get.left(), 0u);
  EXPECT_EQ(a[3].type, type::kSetVariables);
  AsebaReader set(a[3].payload);
  EXPECT_EQ(*set.word(), 7);
  EXPECT_EQ(*set.word(), 57);
  EXPECT_EQ(static_cast<std::int16_t>(*set.word()), -1);
  EXPECT_TRUE(a[4].is_user_event());
  EXPECT_EQ(a[4].type, 3);
  EXPECT_EQ(*read_event_args(a[4]), std::vector<std::int16_t>({-1, 0, 500}));
  EXPECT_EQ(whole.stats().messages, 5u);
  EXPECT_EQ(whole.stats().bytes, wire.size());
  // Header layout: length, source, type, little-endian.
  const Bytes ln = list_nodes();
  EXPECT_EQ(ln, (Bytes{std::byte{2}, std::byte{0}, std::byte{0}, std::byte{0}, std::byte{0x11}, std::byte{0xA0},
                       std::byte{5}, std::byte{0}}));
}

TEST(AsebaMessage, EncodersRefuseWhatAPeerWouldDrop) {
  EXPECT_FALSE(user_event(0x8000, {}));
  std::vector<std::int16_t> many(kMaxPayload, 1);
  EXPECT_FALSE(set_variables(1, 0, many));
  EXPECT_FALSE(AsebaWriter().string(std::string(256, 'x')).finish(1, type::kDescription));
}

TEST(AsebaMessage, OversizedLengthIsSkippedUnstoredAndTheNextMessageSurvives) {
  Bytes wire{std::byte{0xD0}, std::byte{0x07}, std::byte{1}, std::byte{0}, std::byte{0x05}, std::byte{0x90}};
  wire.resize(wire.size() + 2000, std::byte{0xAB});  // a 2000-byte payload
  const Bytes good = get_variables(1, 2, 3);
  wire.insert(wire.end(), good.begin(), good.end());
  AsebaDecoder d(1024);
  const auto got = decode_all(wire, d);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, type::kGetVariables);
  EXPECT_EQ(d.stats().oversized, 1u);
  EXPECT_EQ(d.stats().messages, 1u);
}

TEST(AsebaMessage, ReadersRefuseShortAndOddPayloadsWithTheOffset) {
  Message m;
  m.type = type::kVariables;
  m.payload = {std::byte{42}, std::byte{0}, std::byte{1}};  // start, then half a word
  auto v = read_variables(m);
  ASSERT_FALSE(v);
  EXPECT_NE(v.error().find("not a whole number of words"), std::string::npos) << v.error();
  m.payload = {std::byte{9}, std::byte{'a'}};  // a string of 9 with 1 byte
  AsebaReader r(m.payload);
  auto s = r.string();
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().find("at byte 0"), std::string::npos) << s.error();
  m.payload = {};
  EXPECT_FALSE(read_node_present(m));
}

Message described(std::uint16_t source, std::uint16_t type, const AsebaWriter& w) {
  AsebaDecoder d;
  Message out;
  d.feed(*w.finish(source, type), [&](const Message& m) { out = m; });
  return out;
}

Message header(std::uint16_t node, std::uint16_t memory, std::uint16_t count) {
  return described(
      node, type::kDescription,
      AsebaWriter().string("thymio-II").word(5).word(1534).word(32).word(memory).word(count).word(0).word(0));
}

Message variable(std::uint16_t node, std::uint16_t size, const std::string& name) {
  return described(node, type::kNamedVariableDescription, AsebaWriter().word(size).string(name));
}

TEST(AsebaDescription, AddressesAreTheRunningSumOfSizesInArrivalOrder) {
  DescriptionBuilder b(1);
  EXPECT_FALSE(b.take(variable(2, 1, "other node")));  // another node's: not ours
  EXPECT_TRUE(b.take(header(1, 20, 3)));
  EXPECT_TRUE(b.take(variable(1, 2, "a")));
  EXPECT_FALSE(b.complete());
  EXPECT_TRUE(b.take(variable(1, 7, "prox.horizontal")));
  EXPECT_TRUE(b.take(variable(1, 1, "c")));
  ASSERT_TRUE(b.complete()) << b.error();
  const NodeDescription& d = b.description();
  EXPECT_EQ(d.name, "thymio-II");
  EXPECT_EQ(d.variables_size, 20);
  ASSERT_NE(d.find("prox.horizontal"), nullptr);
  EXPECT_EQ(d.find("prox.horizontal")->address, 2);
  EXPECT_EQ(d.find("c")->address, 9);
  EXPECT_TRUE(d.holds(13, 7));
  EXPECT_FALSE(d.holds(14, 7));
}

TEST(AsebaDescription, ImpossibleDescriptionsAreRefusedWithTheReason) {
  struct Case {
    std::vector<Message> messages;
    std::string says;
  };
  const std::vector<Case> cases = {
      {{header(1, 10, 2), variable(1, 8, "a"), variable(1, 4, "b")}, "ends past the node's 10 words"},
      {{header(1, 10, 2), variable(1, 1, "a"), variable(1, 1, "a")}, "described twice"},
      {{header(1, 10, 1), variable(1, 1, "a"), variable(1, 1, "b")}, "more named variables"},
      {{header(1, 10, 1), variable(1, 0, "a")}, "size 0"},
      {{header(1, 10, 1), variable(1, 1, "")}, "no name"},
      {{header(1, 40000, 1)}, "more than 32768"},
      {{header(1, 10, 11)}, "11 named variables in 10 words"},
      {{variable(1, 1, "a")}, "before the node's description"},
      {{header(1, 10, 1), header(1, 10, 1)}, "a second description"},
      {{described(1, type::kDescription, AsebaWriter().string("x").word(5))}, "past the payload's end"},
  };
  for (const Case& c : cases) {
    DescriptionBuilder b(1);
    for (const Message& m : c.messages) b.take(m);
    EXPECT_FALSE(b.complete());
    EXPECT_NE(b.error().find(c.says), std::string::npos) << "error: '" << b.error() << "', wanted: " << c.says;
  }
}

// A host and the fake node over TCP.
struct AsebaLinkFixture : ::testing::Test {
  void SetUp() override {
    ASSERT_TRUE(node.listen());
    auto s = TcpStream::connect("127.0.0.1", node.port(), kAnswer);
    ASSERT_TRUE(s) << s.error();
    link = std::make_unique<AsebaLink>(std::shared_ptr<IOStream>(std::move(s).value()));
  }
  symb::testing::FakeAsebaNode node;
  std::unique_ptr<AsebaLink> link;
};

TEST_F(AsebaLinkFixture, FindsDescribesReadsWritesAndExchangesEvents) {
  auto id = link->discover(kAnswer);
  ASSERT_TRUE(id) << id.error();
  EXPECT_EQ(*id, 1);
  auto d = link->describe(*id, kAnswer);
  ASSERT_TRUE(d) << d.error();
  EXPECT_EQ(d->name, "thymio-II");
  ASSERT_NE(d->find("prox.horizontal"), nullptr);
  EXPECT_EQ(d->find("prox.horizontal")->address, 42);
  EXPECT_EQ(d->find("motor.left.target")->address, 57);

  node.poke(44, 1234);
  auto v = link->get(*d, 42, 7, kAnswer);
  ASSERT_TRUE(v) << v.error();
  EXPECT_EQ((*v)[2], 1234);
  const std::int16_t targets[2] = {-200, 300};
  ASSERT_TRUE(link->set(*d, 57, targets));
  auto back = link->get(*d, 57, 2, kAnswer);  // the node handles messages in order: the set came first
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(*back, std::vector<std::int16_t>({-200, 300}));
  // Outside the node's memory: refused before anything is sent.
  EXPECT_FALSE(link->set(*d, 99, targets));
  EXPECT_FALSE(link->get(*d, 95, 7, 10ms));

  std::vector<std::int16_t> heard;
  link->on_event([&](std::uint16_t source, std::uint16_t event, std::span<const std::int16_t> args) {
    EXPECT_EQ(source, 1);
    EXPECT_EQ(event, 4);
    heard.assign(args.begin(), args.end());
  });
  const std::int16_t args[2] = {7, -7};
  ASSERT_TRUE(link->emit(4, args));
  const auto until = std::chrono::steady_clock::now() + kAnswer;
  while (heard.empty() && std::chrono::steady_clock::now() < until) ASSERT_TRUE(link->pump(20ms));
  EXPECT_EQ(heard, std::vector<std::int16_t>({7, -7}));
  const LinkStats s = link->stats();
  EXPECT_EQ(s.user_events, 1u);
  EXPECT_EQ(s.refused(), 0u);
  EXPECT_EQ(s.requests, 2u);
  EXPECT_EQ(s.replies, 2u);
}

TEST_F(AsebaLinkFixture, AFailingNodeGivesAnErrorNotAWait) {
  auto d = link->describe(9, 200ms);  // nobody is node 9
  ASSERT_FALSE(d);
  EXPECT_NE(d.error().find("did not describe itself"), std::string::npos) << d.error();
  auto id = link->discover(kAnswer);
  ASSERT_TRUE(id);
  auto desc = link->describe(*id, kAnswer);
  ASSERT_TRUE(desc);
  node.set_answering(false);
  auto v = link->get(*desc, 42, 7, 100ms);
  ASSERT_FALSE(v);
  EXPECT_NE(v.error().find("did not answer"), std::string::npos) << v.error();
  EXPECT_EQ(link->stats().timeouts, 1u);
  node.close();
  kernel::Status st;
  const auto until = std::chrono::steady_clock::now() + kAnswer;
  while (st && std::chrono::steady_clock::now() < until) st = link->pump(20ms);
  EXPECT_FALSE(st);  // the end of the stream is an error
}

// A node that sends garbage between good answers: the host counts and drops it, and still gets
// the answer it asked for.
TEST(AsebaLink, HostileRepliesAreCountedAndDropped) {
  auto l = TcpListener::bind();
  ASSERT_TRUE(l);
  auto listener = std::move(l).value();
  std::thread evil([&] {
    auto s = listener->accept(kAnswer);
    if (!s || !*s) return;
    auto& out = **s;
    auto w = [&](std::uint16_t type, const AsebaWriter& p) { (void)out.write_all(*p.finish(1, type)); };
    // Describes itself at once (the host's request is read below with the get).
    w(type::kDescription, AsebaWriter().string("thymio-II").word(5).word(0).word(0).word(10).word(1).word(0).word(0));
    w(type::kNamedVariableDescription, AsebaWriter().word(10).string("mem"));
    // Wait for the get, then: a reply outside memory, half a word, an unasked block, an
    // oversized message, and at last the answer.
    std::vector<std::byte> buf(256);
    AsebaDecoder requests;
    bool asked = false;
    while (!asked) {
      auto n = out.read_some(buf, kAnswer);
      if (!n || *n == 0) return;
      requests.feed(std::span<const std::byte>(buf.data(), *n),
                    [&](const Message& m) { asked = asked || m.type == type::kGetVariables; });
    }
    w(type::kVariables, AsebaWriter().word(8).word(1).word(2).word(3));  // 8..10: outside
    w(type::kVariables, AsebaWriter().word(0).word(1).string(""));       // 2.5 words
    w(type::kVariables, AsebaWriter().word(1).word(5));                  // another block
    Bytes big{std::byte{0xFF}, std::byte{0x0F}, std::byte{1}, std::byte{0}, std::byte{5}, std::byte{0x90}};
    big.resize(6 + 0x0FFF, std::byte{0x55});
    (void)out.write_all(big);
    w(type::kVariables, AsebaWriter().word(0).word(11).word(22));
    (void)out.read_some(buf, kAnswer);
  });
  auto s = TcpStream::connect("127.0.0.1", listener->port(), kAnswer);
  ASSERT_TRUE(s) << s.error();
  AsebaLink link(std::shared_ptr<IOStream>(std::move(s).value()));
  auto d = link.describe(1, kAnswer);
  ASSERT_TRUE(d) << d.error();
  auto v = link.get(*d, 0, 2, kAnswer);
  ASSERT_TRUE(v) << v.error();
  EXPECT_EQ(*v, std::vector<std::int16_t>({11, 22}));
  const LinkStats st = link.stats();
  EXPECT_EQ(st.bad_address, 1u);
  EXPECT_EQ(st.malformed, 1u);
  EXPECT_EQ(st.unasked, 1u);
  EXPECT_EQ(st.decoder.oversized, 1u);
  EXPECT_EQ(st.refused(), 3u);
  link.stream().close();
  evil.join();
}

}  // namespace
}  // namespace symb::io::aseba
