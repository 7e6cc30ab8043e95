// AsebaThymio (robot/thymio_aseba) against a fake Aseba node on a local TCP port: a node that is
// not a Thymio is refused by name; prox.horizontal reaches the `ir` device with the simulation's
// channels (clamped into [0, kIrMax]) and prox.ground.reflected the `ground` device (/ 1023); wheel commands reach
// motor.*.target (scaled); the measured speeds give odometry; and a lost link (the node's end closed, or a node that
// stops answering) stops the wheels, refuses commands while down, and comes back on the same port with zero targets
// written first.
#include "symb/robot/thymio_aseba.hpp"

#include <chrono>
#include <mutex>
#include <thread>

#include <gtest/gtest.h>

#include "symb/io/tcp_stream.hpp"
#include "symb/robot/thymio_ir.hpp"

#include "support/aseba_node.hpp"
#include "support/eventually.hpp"

namespace symb::robot::thymio {
namespace {

using namespace std::chrono_literals;
using symb::testing::eventually;
using symb::testing::FakeAsebaNode;

std::shared_ptr<io::IOStream> connect_to(const FakeAsebaNode& node) {
  auto s = io::TcpStream::connect("127.0.0.1", node.port(), 2s);
  EXPECT_TRUE(s) << s.error();
  return s ? std::shared_ptr<io::IOStream>(std::move(s).value()) : nullptr;
}

TEST(ThymioAseba, ANodeThatIsNotAThymioIsRefusedByName) {
  FakeAsebaNode epuck("e-puck", {{"prox", 8}, {"motor.left.target", 1}, {"motor.right.target", 2}});
  ASSERT_TRUE(epuck.listen());
  auto t = AsebaThymio::create(connect_to(epuck));
  auto st = t->connect();
  ASSERT_FALSE(st);
  EXPECT_EQ(st.error(),
            "node 1 'e-puck' is not a Thymio II: no prox.horizontal (7 words), motor.right.target has 2 words, not 1");
  EXPECT_FALSE(t->stats().up);
  // Its wheels take no command.
  ASSERT_TRUE(t->wheels()->open());
  EXPECT_FALSE(t->wheels()->set(std::vector<float>{100, 100}));
}

TEST(ThymioAseba, ProxReachesIrAndWheelCommandsReachTheMotorTargets) {
  FakeAsebaNode node;
  ASSERT_TRUE(node.listen());
  AsebaThymioOptions o;
  o.control_period = 10ms;
  o.speed_scale = 0.5;
  auto t = AsebaThymio::create(connect_to(node), o);
  ASSERT_TRUE(t->connect());
  // The same channels as a simulated Thymio's.
  ASSERT_EQ(t->ir()->channels().size(), kIrCount);
  EXPECT_EQ(t->ir()->channels()[6].name, "ir6");
  EXPECT_EQ(t->ir()->channels()[0].max, static_cast<float>(kIrMax));
  EXPECT_EQ(t->wheels()->channels()[1].name, "right");
  EXPECT_EQ(t->wheels()->channels()[1].max, 500.0f);

  const std::uint16_t prox = node.address_of("prox.horizontal");
  ASSERT_EQ(prox, 42);
  const std::int16_t raw[7] = {0, 100, 2000, 5000, -3, 7, 4505};
  for (std::size_t i = 0; i < 7; ++i) node.poke(prox + i, raw[i]);
  node.poke(node.address_of("prox.ground.reflected"), 1023);
  node.poke(node.address_of("prox.ground.reflected") + 1, 100);
  node.poke(node.address_of("motor.left.speed"), 300);
  node.poke(node.address_of("motor.right.speed"), 300);
  ASSERT_TRUE(t->ir()->open());
  ASSERT_TRUE(t->ground()->open());
  t->start();
  ASSERT_TRUE(eventually([&] { return t->stats().samples >= 5; }));
  auto s = t->ir()->latest();
  ASSERT_TRUE(s);
  EXPECT_EQ(std::vector<float>(s->numbers().begin(), s->numbers().end()),
            (std::vector<float>{0, 100, 2000, static_cast<float>(kIrMax), 0, 7, 4505}));
  EXPECT_EQ(t->ir()->stats().clamped_values % 2, 0u);  // 5000 and -3, in every sample
  auto g = t->ground()->latest();
  ASSERT_TRUE(g);
  EXPECT_EQ(g->numbers()[0], 1.0f);
  EXPECT_FLOAT_EQ(g->numbers()[1], 100.0f / 1023.0f);

  ASSERT_TRUE(t->wheels()->open());
  ASSERT_TRUE(t->wheels()->set(std::vector<float>{400, -250}));
  ASSERT_TRUE(eventually([&] { return node.peek(57) == 200 && node.peek(58) == -125; }));
  const AsebaThymioStats st = t->stats();
  EXPECT_EQ(st.wheel_writes, 1u);
  EXPECT_EQ(st.left_target, 200);
  // Straight ahead at 300 units: odometry moves along x only.
  EXPECT_GT(st.path, 0.0);
  EXPECT_NEAR(st.x, st.path, 1e-9);
  EXPECT_EQ(st.y, 0.0);
  EXPECT_EQ(st.link.refused(), 0u);
  t->stop();
  EXPECT_TRUE(eventually([&] { return node.peek(57) == 0; }));  // stop() leaves the robot standing
}

TEST(ThymioAseba, ALostLinkStopsTheWheelsAndComesBackOnTheSamePort) {
  FakeAsebaNode node;
  ASSERT_TRUE(node.listen());
  const std::uint16_t port = node.port();
  AsebaThymioOptions o;
  o.control_period = 10ms;
  o.reopen_first = 20ms;
  o.reopen_most = 40ms;
  auto t = AsebaThymio::create(connect_to(node), o);
  std::mutex mu;
  std::vector<std::string> reports;
  t->on_report([&](os::LogLevel, std::string_view text) {
    std::lock_guard lock(mu);
    reports.emplace_back(text);
  });
  ASSERT_TRUE(t->connect());
  ASSERT_TRUE(t->wheels()->open());
  t->start();
  ASSERT_TRUE(t->wheels()->set(std::vector<float>{300, 300}));
  ASSERT_TRUE(eventually([&] { return node.peek(57) == 300; }));

  const std::uint64_t stops_before = t->stats().stops;
  node.close();  // the robot's end goes away
  // The loss is counted together with its stop (zero targets): whoever sees the count sees the
  // stop in the same snapshot.
  ASSERT_TRUE(eventually([&] { return t->stats().losses == 1; }));
  AsebaThymioStats st = t->stats();
  EXPECT_EQ(st.stops, stops_before + 1);
  EXPECT_FALSE(st.up);
  EXPECT_EQ(st.left_target, 0);
  EXPECT_LE(st.last_stop_delay, 2 * o.control_period);
  EXPECT_FALSE(t->wheels()->set(std::vector<float>{300, 300}));  // refused while down
  EXPECT_GE(t->stats().wheel_refused, 1u);
  // The loss is counted before it is reported (on the driver's thread): wait for the report.
  ASSERT_TRUE(eventually([&] {
    std::lock_guard lock(mu);
    return !reports.empty();
  }));
  {
    std::lock_guard lock(mu);
    EXPECT_NE(reports.front().find("lost"), std::string::npos) << reports.front();
    EXPECT_NE(reports.front().find("wheels stopped"), std::string::npos) << reports.front();
  }
  const std::uint64_t samples = t->stats().samples;

  ASSERT_TRUE(node.listen(port));  // back on the same port; it still holds 300 as its targets
  ASSERT_TRUE(eventually([&] { return t->stats().reconnects == 1 && t->stats().up; }));
  // Zero targets written before anything else (the node handles them on its own thread).
  EXPECT_TRUE(eventually([&] { return node.peek(57) == 0 && node.peek(58) == 0; }));
  ASSERT_TRUE(eventually([&] { return t->stats().samples > samples + 3; }));
  ASSERT_TRUE(t->wheels()->set(std::vector<float>{-100, 100}));
  ASSERT_TRUE(eventually([&] { return node.peek(57) == -100; }));
  EXPECT_TRUE(eventually([&] {
    std::lock_guard lock(mu);
    return reports.back().find("link back") != std::string::npos;
  }));
}

TEST(ThymioAseba, ANodeThatStopsAnsweringIsLostAndToldToStop) {
  FakeAsebaNode node;
  ASSERT_TRUE(node.listen());
  AsebaThymioOptions o;
  o.control_period = 10ms;
  // Long beside the fake node's answer, so that only silence is a missed read, not a fake node
  // that the other tests on a busy box kept off its core for a moment.
  o.reply_timeout = 300ms;
  o.lost_periods = 3;
  o.reopen_first = 5s;  // no reconnect within the test
  o.reopen_most = 5s;
  auto t = AsebaThymio::create(connect_to(node), o);
  ASSERT_TRUE(t->connect());
  ASSERT_TRUE(t->wheels()->open());
  t->start();
  ASSERT_TRUE(t->wheels()->set(std::vector<float>{250, 250}));
  ASSERT_TRUE(eventually([&] { return node.peek(58) == 250; }));
  node.set_answering(false);
  ASSERT_TRUE(eventually([&] { return t->stats().losses == 1; }));
  // The stream still worked: the stop reached the robot.
  ASSERT_TRUE(eventually([&] { return node.peek(57) == 0 && node.peek(58) == 0; }));
  EXPECT_EQ(t->stats().missed_reads, 3u);  // lost_periods unanswered reads: the last is the loss
  t->stop();
}

TEST(ThymioAseba, StartedWithoutConnectFindsTheRobotItself) {
  FakeAsebaNode node;
  ASSERT_TRUE(node.listen());
  AsebaThymioOptions o;
  o.control_period = 10ms;
  auto t = AsebaThymio::create(connect_to(node), o);
  t->start();
  ASSERT_TRUE(eventually([&] { return t->stats().up && t->stats().samples > 0; }));
  EXPECT_EQ(t->stats().node_name, "thymio-II");
  EXPECT_EQ(t->stats().reconnects, 1u);
  t->stop();
}

}  // namespace
}  // namespace symb::robot::thymio
