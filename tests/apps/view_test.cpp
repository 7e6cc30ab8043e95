// The web view's parts (apps/view/): the bounded frame queue (drops counted, the producer never
// waits), the JSON frames, the server (token, refusal, a stalled client) and `symb run --view`
// end to end in-process with a WebSocket client (the page's protocol without a browser; the
// browser itself is view_browser_test.cjs).
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/apps/evolve/evolve_run.hpp"
#include "symb/apps/run/scenario_run.hpp"
#include "symb/apps/view/frame_queue.hpp"
#include "symb/apps/view/view_json.hpp"
#include "symb/apps/view/view_server.hpp"

#include "support/ws_test_client.hpp"

namespace {

using namespace std::chrono_literals;
using symb::apps::view::FrameQueue;
using symb::testing::WsTestClient;
namespace view = symb::apps::view;

TEST(ViewFrameQueue, WhenFullTheOldestGoesAndIsCounted) {
  FrameQueue q(4);
  for (int i = 0; i < 10; ++i) q.push(std::to_string(i));
  auto s = q.stats();
  EXPECT_EQ(s.pushed, 10u);
  EXPECT_EQ(s.dropped, 6u);
  EXPECT_EQ(s.queued, 4u);
  for (int i = 6; i < 10; ++i) EXPECT_EQ(q.pop(0ms), std::to_string(i));
  EXPECT_EQ(q.pop(0ms), std::nullopt);
  s = q.stats();
  EXPECT_EQ(s.pushed, s.sent + s.dropped + s.queued);
  EXPECT_THROW(FrameQueue(0), std::invalid_argument);
}

TEST(ViewFrameQueue, AProducerWithoutAnyConsumerNeverWaits) {
  // Nobody pops: a browser that stopped reading. The producer finishes anyway, with every frame
  // beyond the capacity counted.
  FrameQueue q(8);
  std::thread producer([&q] {
    for (int i = 0; i < 100000; ++i) q.push(std::string(100, 'x'));
  });
  producer.join();
  const auto s = q.stats();
  EXPECT_EQ(s.pushed, 100000u);
  EXPECT_EQ(s.dropped, 100000u - 8u);
  EXPECT_EQ(s.queued, 8u);
}

TEST(ViewFrameQueue, CloseWakesTheConsumerAndCountsWhatWasLeft) {
  FrameQueue q(4);
  std::optional<std::string> got = "not yet";
  std::thread consumer([&] { got = q.pop(std::chrono::seconds(30)); });
  std::this_thread::sleep_for(20ms);
  q.close();
  consumer.join();
  EXPECT_EQ(got, std::nullopt);
  FrameQueue r(4);
  r.push("a");
  r.push("b");
  r.close();
  r.push("c");  // discarded, not counted
  const auto s = r.stats();
  EXPECT_EQ(s.pushed, 2u);
  EXPECT_EQ(s.dropped, 2u);
  EXPECT_EQ(s.queued, 0u);
}

TEST(ViewJson, StepIsAFlatNumberListEveryStrideThRobot) {
  std::vector<symb::sim::RobotState> robots(5);
  for (int i = 0; i < 5; ++i) robots[i].pose = {10.0 * i + 0.04, 20.25, std::numbers::pi / 2};
  EXPECT_EQ(view::step_json(7, 0.21, std::span(robots).first(2), 100),
            "{\"type\":\"step\",\"step\":7,\"t\":0.21,\"n\":2,\"stride\":1,\"xy\":[0,20.2,90,10,20.2,90]}\n");
  // Five robots, at most two a frame: every third (0 and 3).
  EXPECT_EQ(view::step_json(1, 1, robots, 2),
            "{\"type\":\"step\",\"step\":1,\"t\":1,\"n\":5,\"stride\":3,\"xy\":[0,20.2,90,30,20.2,90]}\n");
}

TEST(ViewJson, GraphCarriesTasksAndHooksWithTheirCounters) {
  symb::os::TaskInfo t;
  t.name = "controller";
  t.type = "mdl2e";
  t.state = symb::os::TaskState::kRunning;
  t.priority = 2;
  t.period = 30ms;
  t.queue_depth = 1;
  t.queue_capacity = 8;
  t.traffic.delivered = 40;
  t.traffic.suppressed = 3;
  symb::os::HookInfo h;
  h.id.serial = 4;
  h.sender_name = "ir";
  h.receiver_name = "controller";
  h.options.priority = 5;
  h.options.suppress_window = 100ms;
  h.accounting.sent = 44;
  h.accounting.traffic.attempted = 44;
  h.accounting.traffic.delivered = 40;
  h.accounting.traffic.suppressed = 3;
  h.accounting.queued = 1;
  const std::string j = view::graph_json("thymio", std::span(&t, 1), std::span(&h, 1), 1s);
  EXPECT_NE(j.find("\"type\":\"graph\",\"robot\":\"thymio\",\"t\":1"), std::string::npos) << j;
  EXPECT_NE(j.find("{\"name\":\"controller\",\"type\":\"mdl2e\",\"state\":\"running\",\"priority\":2,\"period\":0.03,"
                   "\"queue\":1,\"capacity\":8,\"in\":40,\"out\":0,\"dropped\":3}"),
            std::string::npos)
      << j;
  EXPECT_NE(j.find("{\"hook\":4,\"sender\":\"ir\",\"receiver\":\"controller\",\"priority\":5,"), std::string::npos)
      << j;
  EXPECT_NE(j.find("\"suppress\":0.1,\"enabled\":true,\"inhibited\":false,\"sent\":44,\"delivered\":40,\"dropped\":3,"
                   "\"suppressed\":3,\"queued\":1}"),
            std::string::npos)
      << j;
}

TEST(ViewJson, HelloHasTheArenaWallsAndRobots) {
  symb::sim::WorldSpec w;
  w.width = 200;
  w.height = 150;
  w.walls.push_back({50, 0, 50, 100, 2, {}});
  view::HelloInfo h;
  h.scenario = "maze";
  h.world = &w;
  h.robots = {"a", "b\"c"};
  h.selected = 1;
  h.speed = 10;
  const std::string j = view::hello_json(h);
  EXPECT_NE(j.find("\"world\":{\"width\":200,\"height\":150,\"walls\":[[50,0,50,100,2]],\"zones\":[]}"),
            std::string::npos)
      << j;
  EXPECT_NE(j.find("\"robots\":[\"a\",\"b\\\"c\"],\"selected\":1,\"virtual\":true,\"paused\":false,\"speed\":10"),
            std::string::npos)
      << j;
}

TEST(ViewServer, AWrongTokenIsRefusedTheRightOneGetsFramesBothWays) {
  std::atomic<int> opened{0};
  std::string said;
  std::mutex said_mu;
  view::ViewServerHandlers handlers;
  handlers.on_open = [&](view::ClientId) { ++opened; };
  handlers.on_message = [&](view::ClientId, std::string_view text) {
    std::lock_guard lock(said_mu);
    said = text;
  };
  view::ViewServerOptions options;
  options.token = "secret";
  auto server = view::ViewServer::start(options, handlers);
  ASSERT_TRUE(server) << server.error();
  view::ViewServer& s = **server;
  EXPECT_EQ(s.host(), "127.0.0.1");
  EXPECT_EQ(s.url(), "http://127.0.0.1:" + std::to_string(s.port()) + "/?token=secret");

  for (const char* path : {"/ws?token=secreT", "/ws?token=secret2", "/ws", "/ws?token="}) {
    WsTestClient bad;
    EXPECT_EQ(bad.open(s.port(), path), "HTTP/1.1 403 Forbidden") << path;
    EXPECT_FALSE(bad.upgraded());
  }
  EXPECT_EQ(s.stats().refused, 4u);
  EXPECT_EQ(opened.load(), 0);

  WsTestClient good;
  good.open(s.port(), "/ws?token=secret");
  ASSERT_TRUE(good.upgraded());
  for (int i = 0; i < 200 && s.client_count() == 0; ++i) std::this_thread::sleep_for(5ms);
  ASSERT_EQ(s.client_count(), 1u);
  s.broadcast("{\"type\":\"status\"}");
  EXPECT_EQ(good.read_frame(), "{\"type\":\"status\"}");
  ASSERT_TRUE(good.send_text("pause"));
  for (int i = 0; i < 200; ++i) {
    {
      std::lock_guard lock(said_mu);
      if (!said.empty()) break;
    }
    std::this_thread::sleep_for(5ms);
  }
  std::lock_guard lock(said_mu);
  EXPECT_EQ(said, "pause");
  EXPECT_EQ(opened.load(), 1);
}

TEST(ViewServer, AStalledClientGetsFramesDroppedAndNeverHoldsTheSender) {
  view::ViewServerOptions options;
  options.queue_frames = 16;
  auto server = view::ViewServer::start(options, {});
  ASSERT_TRUE(server) << server.error();
  view::ViewServer& s = **server;
  WsTestClient stalled;  // upgrades, then never reads
  stalled.open(s.port(), "/ws?token=" + s.token(), 4096);
  ASSERT_TRUE(stalled.upgraded());
  for (int i = 0; i < 200 && s.client_count() == 0; ++i) std::this_thread::sleep_for(5ms);
  ASSERT_EQ(s.client_count(), 1u);
  // 2,000 frames of 64 KB: 128 MB, far beyond what the socket buffers hold. Every broadcast
  // returns; what the client could not take is dropped and counted.
  const std::string frame(64 * 1024, 'x');
  for (int i = 0; i < 2000; ++i) s.broadcast(frame);
  const auto st = s.stats();
  EXPECT_EQ(st.frames.pushed, 2000u);
  EXPECT_GT(st.frames.dropped, 1000u);
  EXPECT_LE(st.frames.queued, 16u);
  EXPECT_EQ(st.frames.pushed, st.frames.sent + st.frames.dropped + st.frames.queued);
}

// `symb run --view` in-process: a client connects as the URL is announced (before the run
// starts), asks the page's shell for the robot's hooks and reads what a page would.
TEST(ViewRun, AClientSeesTheWorldTheRobotTheGraphAndItsShellReplies) {
  symb::apps::run::RunOptions o;
  o.scenario_path = std::string(SYMB_SCENARIO_DIR) + "/maze.yaml";
  o.duration = 1s;
  o.speed = 2;  // 0.5 s of wall clock: time for the shell's reply to come back
  o.view.on = true;
  // The client reads as a browser would, on its own thread, and closes when the server says
  // goodbye at the end of the run.
  WsTestClient client;
  std::vector<std::string> frames;
  std::thread reader;
  o.on_notice = [&](const std::string& line) {
    const auto port = line.find(":", line.find("127.0.0.1")) + 1;
    const auto slash = line.find('/', port);
    client.open(static_cast<std::uint16_t>(std::stoi(line.substr(port, slash - port))),
                "/ws" + line.substr(line.find("?token=")));
    client.send_text("shell hooks");
    reader = std::thread([&] {
      for (auto f = client.read_frame(5000ms); f; f = client.read_frame(5000ms)) frames.push_back(*f);
      client.close();
    });
  };
  auto result = symb::apps::run::run_scenario(o);
  if (reader.joinable()) reader.join();
  ASSERT_TRUE(result) << result.error();
  ASSERT_TRUE(client.upgraded());
  const auto has = [&](const std::string& type, const std::string& part) {
    for (const auto& f : frames)
      if (f.find("{\"type\":\"" + type + "\"") == 0 && f.find(part) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(has("hello", "\"walls\":[[50,0,50,100,2]")) << frames.size() << " frames";
  EXPECT_TRUE(has("step", "\"xy\":[25,"));
  EXPECT_TRUE(has("graph", "\"sender\":\"ir\",\"receiver\":\"controller\""));
  EXPECT_TRUE(has("shell", "controller")) << "the shell's `hooks` reply";
  EXPECT_TRUE(has("status", "\"finished\":true"));
  // The view only looks: the run is the one without it, bit for bit.
  symb::apps::run::RunOptions plain;
  plain.scenario_path = o.scenario_path;
  plain.duration = o.duration;
  auto unseen = symb::apps::run::run_scenario(plain);
  ASSERT_TRUE(unseen) << unseen.error();
  EXPECT_EQ(result->trajectory_hash, unseen->trajectory_hash);
  EXPECT_EQ(result->steps, unseen->steps);
}

// `symb evolve --view`: the same page on an evolution run, the evolving robot shown first, and
// the evolution's result unchanged by the view (same evaluations, same history).
TEST(ViewRun, AnEvolutionRunIsShownWithItsEvolvingRobotAndRunsTheSame) {
  const std::string scenario = std::string(SYMB_SCENARIO_DIR) + "/evolve_maze.yaml";
  const auto out = std::filesystem::temp_directory_path() / ("symb_view_evolve_" + std::to_string(::getpid()));
  symb::apps::evolve::EvolveOptions plain;
  plain.scenario_path = scenario;
  plain.duration = 2min;
  plain.checkpoint_every = symb::kernel::Duration{0};
  plain.out_dir = out / "plain";
  symb::apps::evolve::EvolveOptions viewed = plain;
  viewed.out_dir = out / "viewed";
  viewed.view.on = true;
  WsTestClient client;
  std::vector<std::string> frames;
  std::thread reader;
  viewed.on_notice = [&](const std::string& line) {
    const auto port = line.find(":", line.find("127.0.0.1")) + 1;
    const auto slash = line.find('/', port);
    client.open(static_cast<std::uint16_t>(std::stoi(line.substr(port, slash - port))),
                "/ws" + line.substr(line.find("?token=")));
    reader = std::thread([&] {
      for (auto f = client.read_frame(5000ms); f; f = client.read_frame(5000ms)) frames.push_back(*f);
      client.close();
    });
  };
  auto a = symb::apps::evolve::run_evolution(plain);
  auto b = symb::apps::evolve::run_evolution(viewed);
  if (reader.joinable()) reader.join();
  std::filesystem::remove_all(out);
  ASSERT_TRUE(a) << a.error();
  ASSERT_TRUE(b) << b.error();
  EXPECT_GT(a->evaluations, 0u);
  EXPECT_EQ(a->evaluations, b->evaluations);
  EXPECT_EQ(a->history_hash, b->history_hash);
  ASSERT_TRUE(client.upgraded());
  const auto has = [&](const std::string& type, const std::string& part) {
    for (const auto& f : frames)
      if (f.find("{\"type\":\"" + type + "\"") == 0 && f.find(part) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(has("hello", "\"scenario\":\"evolve_maze\"")) << frames.size() << " frames";
  EXPECT_TRUE(has("graph", "{\"name\":\"evolution\",\"type\":\"one_plus_one\""));
  EXPECT_TRUE(has("status", "\"finished\":true"));
}

}  // namespace
