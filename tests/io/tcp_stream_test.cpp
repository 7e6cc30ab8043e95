#include "symb/io/tcp_stream.hpp"

#include <algorithm>
#include <atomic>
#include <thread>

#include <gtest/gtest.h>

#include "io_test_support.hpp"

namespace symb::io {
namespace {

using namespace std::chrono_literals;
using symb::testing::eventually;
using testing::read_exactly;
using testing::Writer;

struct Connected {
  std::unique_ptr<TcpListener> listener;
  std::unique_ptr<TcpStream> client;
  std::unique_ptr<TcpStream> server;
};

Connected connect_pair() {
  Connected c;
  auto l = TcpListener::bind();
  if (!l) {
    ADD_FAILURE() << l.error();
    return c;
  }
  c.listener = std::move(l).value();
  auto client = TcpStream::connect("127.0.0.1", c.listener->port(), 5s);
  if (!client) {
    ADD_FAILURE() << client.error();
    return c;
  }
  c.client = std::move(client).value();
  auto server = c.listener->accept(testing::kDeadline);
  if (!server || !*server) {
    ADD_FAILURE() << (server ? std::string("no connection came") : server.error());
    return c;
  }
  c.server = std::move(server).value();
  return c;
}

TEST(TcpStream, BytesAndValuesGoBothWays) {
  Connected c = connect_pair();
  ASSERT_TRUE(c.client && c.server);
  EXPECT_EQ(c.listener->host(), "127.0.0.1");
  EXPECT_NE(c.listener->port(), 0);
  EXPECT_TRUE(c.client->is_open());
  EXPECT_TRUE(c.server->is_open());
  EXPECT_EQ(c.client->peer(), "127.0.0.1:" + std::to_string(c.listener->port()));
  auto info = c.server->ioctl("info");
  ASSERT_TRUE(info);
  EXPECT_NE(info->find("peer=127.0.0.1:"), std::string::npos) << *info;
  EXPECT_NE(info->find("nodelay=true"), std::string::npos) << *info;

  // Bulk both ways at once: more than the socket buffers hold, so writes really wait for room.
  std::vector<std::byte> up(3 << 20), down(2 << 20);
  for (std::size_t i = 0; i < up.size(); ++i) up[i] = static_cast<std::byte>((i * 7) & 0xff);
  for (std::size_t i = 0; i < down.size(); ++i) down[i] = static_cast<std::byte>((i * 13) & 0xff);
  Writer w_up(*c.client, up, 65536);
  Writer w_down(*c.server, down, 65536);
  std::vector<std::byte> at_client;
  std::thread reader([&] { at_client = read_exactly(*c.client, down.size()); });
  const auto at_server = read_exactly(*c.server, up.size());
  reader.join();
  EXPECT_EQ(w_up.join(), "");
  EXPECT_EQ(w_down.join(), "");
  EXPECT_TRUE(at_server == up) << "upstream bytes differ";
  EXPECT_TRUE(at_client == down) << "downstream bytes differ";

  // The C++ stream operators work over TCP as over any IOStream.
  *c.client << 42 << ' ' << 2.5 << " robot\n";
  ASSERT_TRUE(*c.client);
  int n = 0;
  double x = 0;
  std::string word;
  c.server->set_read_timeout(testing::kDeadline);
  *c.server >> n >> x >> word;
  ASSERT_TRUE(*c.server);
  EXPECT_EQ(n, 42);
  EXPECT_EQ(x, 2.5);
  EXPECT_EQ(word, "robot");
}

TEST(TcpListener, AcceptsEveryConnectionAndTimesOutWhenNoneComes) {
  auto l = TcpListener::bind("127.0.0.1", 0);
  ASSERT_TRUE(l) << l.error();
  auto none = (*l)->accept(20ms);
  ASSERT_TRUE(none) << none.error();
  EXPECT_TRUE(none.value() == nullptr);

  std::vector<std::unique_ptr<TcpStream>> clients, servers;
  for (int i = 0; i < 5; ++i) {
    auto cl = TcpStream::connect("localhost", (*l)->port(), 5s);
    ASSERT_TRUE(cl) << cl.error();
    clients.push_back(std::move(cl).value());
  }
  for (int i = 0; i < 5; ++i) {
    auto s = (*l)->accept(testing::kDeadline);
    ASSERT_TRUE(s && *s) << (s ? "timed out" : s.error());
    servers.push_back(std::move(s).value());
  }
  // Each accepted stream is joined to its own client.
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(clients[static_cast<std::size_t>(i)]->write_all(as_bytes(std::to_string(i))));
  std::string seen;
  for (auto& s : servers) {
    auto got = read_exactly(*s, 1);
    ASSERT_EQ(got.size(), 1u);
    seen.push_back(static_cast<char>(got[0]));
  }
  std::sort(seen.begin(), seen.end());
  EXPECT_EQ(seen, "01234");
}

TEST(TcpStream, ConnectingToAClosedPortFailsClearly) {
  std::uint16_t port = 0;
  {
    auto l = TcpListener::bind();
    ASSERT_TRUE(l);
    port = (*l)->port();
  }  // closed again: nothing listens there now
  auto s = TcpStream::connect("127.0.0.1", port, 5s);
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().find("cannot connect to 127.0.0.1:" + std::to_string(port)), std::string::npos) << s.error();
  EXPECT_NE(s.error().find("refused"), std::string::npos) << s.error();

  auto zero = TcpStream::connect("127.0.0.1", 0, 1s);
  ASSERT_FALSE(zero);
  EXPECT_NE(zero.error().find("port 0"), std::string::npos) << zero.error();
  auto nowhere = TcpStream::connect("no-such-host.invalid", 80, 1s);
  ASSERT_FALSE(nowhere);
  EXPECT_NE(nowhere.error().find("no-such-host.invalid"), std::string::npos) << nowhere.error();
  auto bad_bind = TcpListener::bind("256.1.1.1", 0);
  ASSERT_FALSE(bad_bind);
  EXPECT_NE(bad_bind.error().find("256.1.1.1"), std::string::npos) << bad_bind.error();
}

TEST(TcpStream, CloseFromAnotherThreadWakesABlockedReader) {
  Connected c = connect_pair();
  ASSERT_TRUE(c.client && c.server);
  testing::expect_close_wakes_blocked_reader(*c.server);
  EXPECT_FALSE(c.server->open()) << "an accepted connection cannot connect again";

  // The client sees the connection end.
  std::byte buf[8];
  ASSERT_TRUE(eventually([&] { return !c.client->read_some(buf, 10ms).ok(); }));
  EXPECT_FALSE(c.client->is_open());
  EXPECT_NE(c.client->failure().find("end of stream"), std::string::npos) << c.client->failure();
}

TEST(TcpListener, CloseFromAnotherThreadWakesABlockedAccept) {
  auto l = TcpListener::bind();
  ASSERT_TRUE(l);
  std::atomic<pid_t> tid{0};
  std::string error;
  std::thread acceptor([&] {
    tid = testing::this_thread_tid();
    auto r = (*l)->accept(60s);
    if (!r) error = r.error();
  });
  ASSERT_TRUE(eventually([&] { return tid.load() != 0 && testing::thread_sleeping(tid.load()); }));
  const auto t0 = std::chrono::steady_clock::now();
  (*l)->close();
  acceptor.join();
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 10s);
  EXPECT_NE(error.find("closed"), std::string::npos) << error;
  EXPECT_FALSE((*l)->is_open());
}

TEST(TcpStream, AClientReconnectsWithOpen) {
  auto l = TcpListener::bind();
  ASSERT_TRUE(l);
  auto cl = TcpStream::connect("127.0.0.1", (*l)->port());
  ASSERT_TRUE(cl) << cl.error();
  auto first = (*l)->accept(testing::kDeadline);
  ASSERT_TRUE(first && *first);
  (*cl)->close();
  EXPECT_FALSE((*cl)->is_open());
  ASSERT_TRUE((*cl)->open());
  auto second = (*l)->accept(testing::kDeadline);
  ASSERT_TRUE(second && *second);
  ASSERT_TRUE((*cl)->write_all(as_bytes("again")));
  EXPECT_EQ(read_exactly(**second, 5).size(), 5u);
}

}  // namespace
}  // namespace symb::io
