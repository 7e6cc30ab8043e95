// The web view's parts (apps/view/): the bounded frame queue (drops counted, the producer never
// waits), the bounded probe history, the JSON frames, the server (token, refusal, a stalled
// client) and `symb run --view` (2D, a spiking network, a 3D organism), `symb evolve --view` and
// `symb board --view` end to end with a WebSocket client (the page's protocol without a browser;
// the browser itself is view_browser_test.cjs).
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/apps/evolve/evolve_run.hpp"
#include "symb/apps/run/scenario_run.hpp"
#include "symb/apps/view/frame_queue.hpp"
#include "symb/apps/view/probe_history.hpp"
#include "symb/apps/view/view_json.hpp"
#include "symb/apps/view/view_server.hpp"

#include "support/eventually.hpp"
#include "support/symb_child.hpp"
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
  // A frame taken is still queued until the consumer says it went out (sent) or not (dropped).
  EXPECT_EQ(q.pop(0ms), "6");
  EXPECT_EQ(q.stats().queued, 4u);
  q.done(false);
  EXPECT_EQ(q.stats().queued, 3u);
  EXPECT_EQ(q.stats().dropped, 7u);
  for (int i = 7; i < 10; ++i) {
    EXPECT_EQ(q.pop(0ms), std::to_string(i));
    q.done(true);
  }
  EXPECT_EQ(q.pop(0ms), std::nullopt);
  s = q.stats();
  EXPECT_EQ(s.sent, 3u);
  EXPECT_EQ(s.queued, 0u);
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
  symb::testing::eventually([&] { return s.client_count() != 0; });
  ASSERT_EQ(s.client_count(), 1u);
  s.broadcast("{\"type\":\"status\"}");
  EXPECT_EQ(good.read_frame(), "{\"type\":\"status\"}");
  ASSERT_TRUE(good.send_text("pause"));
  symb::testing::eventually([&] {
    std::lock_guard lock(said_mu);
    return !said.empty();
  });
  std::lock_guard lock(said_mu);
  EXPECT_EQ(said, "pause");
  EXPECT_EQ(opened.load(), 1);
}

// Starts `server`, queueing `queue_frames` per client, and connects `client` to it through a 4 KB
// receive buffer (frames soon back up into the server's queue). The caller declares the server
// first, so that the client closes first and the server's stop does not wait for it.
void start_with_client(std::unique_ptr<view::ViewServer>& server, std::size_t queue_frames, WsTestClient& client) {
  view::ViewServerOptions options;
  options.queue_frames = queue_frames;
  auto started = view::ViewServer::start(options, {});
  ASSERT_TRUE(started) << started.error();
  server = std::move(started).value();
  client.open(server->port(), "/ws?token=" + server->token(), 4096);
  ASSERT_TRUE(client.upgraded());
  for (int i = 0; i < 2000 && server->client_count() == 0; ++i) std::this_thread::sleep_for(5ms);
  ASSERT_EQ(server->client_count(), 1u);
}

TEST(ViewServer, AStalledClientGetsFramesDroppedAndNeverHoldsTheSender) {
  std::unique_ptr<view::ViewServer> server;
  WsTestClient stalled;  // upgrades, then never reads
  start_with_client(server, 16, stalled);
  ASSERT_FALSE(HasFatalFailure());
  view::ViewServer& s = *server;
  // 2,000 frames of 64 KB: 128 MB, far beyond what the socket buffers hold. Every broadcast
  // returns; what the client could not take is dropped and counted.
  const std::string frame(64 * 1024, 'x');
  for (int i = 0; i < 2000; ++i) s.broadcast(frame);
  const auto st = s.stats();
  EXPECT_EQ(st.frames.pushed, 2000u);
  EXPECT_GT(st.frames.dropped, 1000u);
  EXPECT_LE(st.frames.queued, 16u + 1u);  // the queue, and the frame the sender is stuck writing
  EXPECT_EQ(st.frames.pushed, st.frames.sent + st.frames.dropped + st.frames.queued);
}

// The end of a run waits for a client that keeps reading, however slowly: 64 frames of 128 KB (8
// MB, twice what Linux lets a socket's buffers hold) read one every 40 ms take over a second,
// more than a fixed half-second wait gave them. The last frame (a run's "finished") arrives.
TEST(ViewServer, FlushWaitsForAClientThatKeepsReadingSlowly) {
  std::unique_ptr<view::ViewServer> server;
  WsTestClient slow;
  start_with_client(server, 64, slow);
  ASSERT_FALSE(HasFatalFailure());
  view::ViewServer& s = *server;
  const std::string frame(128 * 1024, 'x');
  for (int i = 0; i < 63; ++i) s.broadcast(frame);
  s.broadcast("last");
  std::atomic<int> read{0};
  std::atomic<bool> got_last{false};
  std::thread reader([&] {
    while (auto f = slow.read_frame(5000ms)) {
      ++read;
      if (*f == "last") {
        got_last = true;
        return;
      }
      std::this_thread::sleep_for(40ms);
    }
  });
  const auto started = std::chrono::steady_clock::now();
  const bool flushed = s.flush(2s, 60s);
  const auto took = std::chrono::steady_clock::now() - started;
  reader.join();
  EXPECT_TRUE(flushed);
  EXPECT_TRUE(got_last) << read.load() << " frames read";
  EXPECT_GT(took, 500ms) << "the client was not slow: nothing here tells the flush from a fixed wait";
  const auto st = s.stats();
  EXPECT_EQ(st.frames.queued, 0u);
  EXPECT_EQ(st.frames.pushed, st.frames.sent + st.frames.dropped);
}

// civetweb writes nothing once it is told to stop. A frame still being written when the run ends
// (16 MB, which the socket's buffers cannot hold, to a client that starts reading 300 ms late)
// must go out whole before the stop, and the client must then be told goodbye: the flush waits
// for the write, not only for the sender to take the frame, and the server's stop waits for its
// senders. Otherwise a page missed a run's last frame ("finished") and waited 2 s for the end.
TEST(ViewServer, AFrameBeingWrittenAtTheStopArrivesWholeAndTheClientIsToldGoodbye) {
  std::unique_ptr<view::ViewServer> server;
  WsTestClient client;
  start_with_client(server, 8, client);
  ASSERT_FALSE(HasFatalFailure());
  std::string big(16 << 20, 'x');
  big.back() = '!';
  server->broadcast("first");
  server->broadcast(big);
  std::vector<std::size_t> sizes;
  bool whole = false;
  std::thread reader([&] {
    std::this_thread::sleep_for(300ms);
    while (auto f = client.read_frame(5000ms)) {
      sizes.push_back(f->size());
      whole = whole || *f == big;
    }
    client.close();
  });
  EXPECT_TRUE(server->flush(5s, 60s));
  const auto st = server->stats();
  server.reset();
  reader.join();
  EXPECT_EQ(st.frames.queued, 0u);
  EXPECT_EQ(st.frames.sent, 2u);
  EXPECT_EQ(sizes.size(), 2u);
  EXPECT_TRUE(whole) << "the 16 MB frame was cut";
  EXPECT_TRUE(client.told_goodbye());
}

// A client that reads nothing is given up on once it has taken no frame for the stall time, not
// waited for until the limit.
TEST(ViewServer, FlushGivesUpOnAStalledClient) {
  std::unique_ptr<view::ViewServer> server;
  WsTestClient stalled;
  start_with_client(server, 16, stalled);
  ASSERT_FALSE(HasFatalFailure());
  view::ViewServer& s = *server;
  // Frames until the socket's buffers are full and the sender is stuck in its write: no frame has
  // left the queue for four rounds (a sender that is only slow to be scheduled moves on).
  const std::string frame(64 * 1024, 'x');
  std::uint64_t sent = ~std::uint64_t{0};
  for (int round = 0, still = 0; round < 400 && still < 4; ++round) {
    still = s.stats().frames.sent == sent ? still + 1 : 0;
    sent = s.stats().frames.sent;
    for (int i = 0; i < 16; ++i) s.broadcast(frame);
    std::this_thread::sleep_for(50ms);
  }
  ASSERT_GT(s.stats().frames.queued, 0u);
  const auto started = std::chrono::steady_clock::now();
  EXPECT_FALSE(s.flush(300ms, 60s));
  EXPECT_LT(std::chrono::steady_clock::now() - started, 30s);
  EXPECT_GT(s.stats().frames.queued, 0u);
}

// Reads a view's frames as a browser would, from the moment the run announces its URL ("view:
// http://127.0.0.1:PORT/?token=T") until the server says goodbye.
class ViewTestReader {
 public:
  ~ViewTestReader() { join(); }
  void on_notice(const std::string& line) {
    const auto at = line.find("view: ");
    if (at == std::string::npos) return;
    const auto port = line.find(":", line.find("127.0.0.1", at)) + 1;
    const auto slash = line.find('/', port);
    const auto token = line.find("?token=", slash);
    const auto end = line.find_first_of(" \r\n", token);
    client_.open(static_cast<std::uint16_t>(std::stoi(line.substr(port, slash - port))),
                 "/ws" + line.substr(token, end == std::string::npos ? std::string::npos : end - token));
    reader_ = std::thread([this] {
      for (auto f = client_.read_frame(5000ms); f; f = client_.read_frame(5000ms)) {
        std::lock_guard lock(mu_);
        frames_.push_back(*f);
      }
      client_.close();
    });
  }
  void join() {
    if (reader_.joinable()) reader_.join();
  }
  bool upgraded() const { return client_.upgraded(); }
  WsTestClient& client() { return client_; }
  // The frames of `type` that hold `part`.
  std::vector<std::string> frames(const std::string& type, const std::string& part = "") {
    std::lock_guard lock(mu_);
    std::vector<std::string> out;
    for (const auto& f : frames_)
      if (f.find("{\"type\":\"" + type + "\"") == 0 && f.find(part) != std::string::npos) out.push_back(f);
    return out;
  }
  std::size_t size() {
    std::lock_guard lock(mu_);
    return frames_.size();
  }

 private:
  WsTestClient client_;
  std::mutex mu_;
  std::vector<std::string> frames_;
  std::thread reader_;
};

// The numbers of a flat JSON array `"key":[...]` in a frame (null as NaN).
std::vector<double> view_test_numbers(const std::string& frame, const std::string& key) {
  std::vector<double> out;
  auto at = frame.find("\"" + key + "\":[");
  if (at == std::string::npos) return out;
  at += key.size() + 4;
  const auto end = frame.find(']', at);
  std::stringstream s(frame.substr(at, end - at));
  for (std::string cell; std::getline(s, cell, ',');) out.push_back(cell == "null" ? std::nan("") : std::stod(cell));
  return out;
}

// The view only looks: the run `viewed` made with the view is the one without it, bit for bit.
void expect_the_run_without_the_view(const symb::apps::run::RunOptions& viewed,
                                     const symb::apps::run::RunResult& result) {
  symb::apps::run::RunOptions plain;
  plain.scenario_path = viewed.scenario_path;
  plain.duration = viewed.duration;
  auto unseen = symb::apps::run::run_scenario(plain);
  ASSERT_TRUE(unseen) << unseen.error();
  EXPECT_EQ(result.trajectory_hash, unseen->trajectory_hash);
  EXPECT_EQ(result.steps, unseen->steps);
}

// `symb run SCENARIO --view 0` for `duration` at `speed`, in-process, read by `reader` (`o` keeps
// the options, for the run without the view).
symb::kernel::Result<symb::apps::run::RunResult> view_test_run(symb::apps::run::RunOptions& o,
                                                               const std::string& scenario,
                                                               symb::kernel::Duration duration, double speed,
                                                               ViewTestReader& reader) {
  o.scenario_path = std::string(SYMB_SCENARIO_DIR) + "/" + scenario;
  o.duration = duration;
  o.speed = speed;
  o.view.on = true;
  o.on_notice = [&reader](const std::string& line) { reader.on_notice(line); };
  auto result = symb::apps::run::run_scenario(o);
  reader.join();
  return result;
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
  ViewTestReader reader;
  o.on_notice = [&](const std::string& line) {
    reader.on_notice(line);
    reader.client().send_text("shell hooks");
  };
  auto result = symb::apps::run::run_scenario(o);
  reader.join();
  ASSERT_TRUE(result) << result.error();
  ASSERT_TRUE(reader.upgraded());
  EXPECT_FALSE(reader.frames("hello", "\"walls\":[[50,0,50,100,2]").empty()) << reader.size() << " frames";
  EXPECT_FALSE(reader.frames("step", "\"xy\":[25,").empty());
  EXPECT_FALSE(reader.frames("graph", "\"sender\":\"ir\",\"receiver\":\"controller\"").empty());
  EXPECT_FALSE(reader.frames("shell", "controller").empty()) << "the shell's `hooks` reply";
  EXPECT_FALSE(reader.frames("status", "\"finished\":true").empty());
  expect_the_run_without_the_view(o, *result);
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
  ViewTestReader reader;
  viewed.on_notice = [&](const std::string& line) { reader.on_notice(line); };
  auto a = symb::apps::evolve::run_evolution(plain);
  auto b = symb::apps::evolve::run_evolution(viewed);
  reader.join();
  std::filesystem::remove_all(out);
  ASSERT_TRUE(a) << a.error();
  ASSERT_TRUE(b) << b.error();
  EXPECT_GT(a->evaluations, 0u);
  EXPECT_EQ(a->evaluations, b->evaluations);
  EXPECT_EQ(a->history_hash, b->history_hash);
  ASSERT_TRUE(reader.upgraded());
  EXPECT_FALSE(reader.frames("hello", "\"scenario\":\"evolve_maze\"").empty()) << reader.size() << " frames";
  EXPECT_FALSE(reader.frames("graph", "{\"name\":\"evolution\",\"type\":\"one_plus_one\"").empty());
  // The fitness plot's series: every evaluation's fitness, one point per evaluation (far fewer
  // than the plot keeps), however many frames they came in (the browser test sees them grow).
  std::size_t fitness_points = 0, frames_with_points = 0;
  for (const auto& f : reader.frames("fitness")) {
    const auto at = f.find("{\"channel\":\"fitness\"");
    if (at == std::string::npos) continue;
    const auto from = f.find("\"points\":[", at) + 10;
    const std::string points = f.substr(from, f.find(']', from) - from);
    if (f.find("\"full\":true") != std::string::npos) fitness_points = 0;  // all again: the page starts over
    if (points.empty()) continue;
    ++frames_with_points;
    fitness_points += static_cast<std::size_t>(std::count(points.begin(), points.end(), ',') + 1) / 2;
  }
  EXPECT_GE(frames_with_points, 1u);
  EXPECT_EQ(fitness_points, b->evaluations) << "a point per evaluation";
  EXPECT_FALSE(reader.frames("status", "\"finished\":true").empty());
}

TEST(ViewProbeHistory, KeepsTheWholeRunInBoundedPointsAndHandsOnOnlyWhatIsNew) {
  view::ProbeHistory h(view::ProbeHistoryOptions{.capacity = 8, .width = 2, .max_series = 2, .max_latest = 3});
  const float v[] = {1, 2, 3, 4};
  h.record("ahhs", "hormones", 0.0, v);
  h.record("ahhs", "hormones", 0.1, v);
  auto first = h.take(false);
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(first[0].width, 2u);
  EXPECT_EQ(first[0].latest, (std::vector<float>{1, 2, 3}));  // max_latest values of the sample
  EXPECT_EQ(first[0].points, (std::vector<double>{0.0, 1, 2, 0.1, 1, 2}));
  EXPECT_TRUE(h.take(false)[0].points.empty()) << "nothing new since the last take";
  // 100 samples in all: the series halves its points as it fills, never above the capacity, and
  // still starts at the run's first instant.
  for (int i = 2; i < 100; ++i) {
    h.record("ahhs", "hormones", 0.1 * i, v);
    ASSERT_LE(h.points("ahhs", "hormones"), 8u) << i;
  }
  auto all = h.take(true);
  ASSERT_EQ(all[0].points.size() % 3, 0u);
  EXPECT_GE(all[0].points.size() / 3, 4u);
  EXPECT_EQ(all[0].points.front(), 0.0);
  EXPECT_GE(all[0].points[all[0].points.size() - 3], 8.0) << "the points reach the latest tenth of the run";
  EXPECT_EQ(all[0].stride, 16u);  // 100 samples in at most 8 points: every 16th kept
  for (std::size_t k = 3; k < all[0].points.size(); k += 3) EXPECT_GT(all[0].points[k], all[0].points[k - 3]);
  // A sample narrower than the series: the missing value is NaN. A third series is refused.
  const float one[] = {5};
  h.record("net", "outputs", 1, one);
  h.record("net", "outputs", 2, v);
  h.record("schema", "vector", 1, v);
  EXPECT_EQ(h.series(), 2u);
  EXPECT_EQ(h.refused_series(), 1u);
  const auto net = h.take(false)[1];
  EXPECT_EQ(net.width, 1u) << "the first sample's width";
  EXPECT_EQ(net.points, (std::vector<double>{1, 5, 2, 1}));
  EXPECT_THROW(
      view::ProbeHistory(view::ProbeHistoryOptions{.capacity = 7, .width = 1, .max_series = 1, .max_latest = 1}),
      std::invalid_argument);
}

TEST(ViewJson, AnOrganismFrameHasPosesHingesAndDockedPairs) {
  const view::ModulePose poses[] = {{{0.1, 0.02, 0.04}, {1, 0, 0, 0}, 0.25},
                                    {{-0.0001, 0, 0.04}, {0.7071, 0, 0, 0.7071}, -1}};
  const view::DockedPair docked[] = {{0, 1, 1, 0}};
  EXPECT_EQ(view::organism_json(12, 0.24, poses, docked),
            "{\"type\":\"organism\",\"step\":12,\"t\":0.24,\"m\":[0.1,0.02,0.04,1,0,0,0,0.25,-0.0001,0,0.04,0.7071,0,0,"
            "0.7071,-1],\"docked\":[[0,1,1,0]]}\n");
  std::vector<view::ModuleShape> shapes(1);
  shapes[0].name = "m0";
  shapes[0].size = {0.1, 0.1, 0.08};
  shapes[0].hinge_axis = {0, 1, 0};
  shapes[0].wheels = true;
  shapes[0].connectors = {{"front", {0.05, 0, 0}}};
  view::HelloInfo h;
  h.scenario = "caterpillar";
  h.organism = &shapes;
  h.robots = {"m0"};
  EXPECT_NE(
      view::hello_json(h).find("\"world\":{\"kind\":\"organism\",\"modules\":[{\"name\":\"m0\",\"size\":[0.1,0.1,"
                               "0.08],\"hinge\":[0,1,0],\"wheels\":true,\"connectors\":[[\"front\",0.05,0,0]]}]}"),
      std::string::npos)
      << view::hello_json(h);
  h.organism = nullptr;  // a board: no world
  EXPECT_NE(view::hello_json(h).find("\"world\":null"), std::string::npos);
}

TEST(ViewJson, ProbeAndFitnessFramesCarryTheirPointsAtAFloatsPrecision) {
  view::ProbeHistory h(view::ProbeHistoryOptions{.capacity = 8, .width = 2, .max_series = 4, .max_latest = 8});
  const float v[] = {0.3f, -1.5f};
  h.record("ahhs", "hormones/a", 1.23456, v);
  const auto s = h.take(true);
  EXPECT_EQ(
      view::probes_json("thymio", s, true),
      "{\"type\":\"probes\",\"robot\":\"thymio\",\"full\":true,\"probes\":[{\"t\":1.23456,\"task\":\"ahhs\","
      "\"channel\":\"hormones/a\",\"values\":[0.3,-1.5],\"width\":2,\"stride\":1,\"points\":[1.235,0.3,-1.5]}]}\n");
  const float spikes[] = {0.5f, 3, 0.501f, 7};
  EXPECT_EQ(view::spikes_json("thymio", "snn", spikes, 2),
            "{\"type\":\"spikes\",\"robot\":\"thymio\",\"task\":\"snn\",\"dropped\":2,\"dots\":[0.5,3,0.501,7]}\n");
  EXPECT_NE(
      view::fitness_json("thymio", "evolution", s, false)
          .find("\"full\":false,\"series\":[{\"channel\":\"hormones/a\",\"width\":2,\"points\":[1.235,0.3,-1.5]}]"),
      std::string::npos);
}

// A spiking network's run (linda_maze): the page gets the network's spikes for its raster, and
// each probe series (the spike rate, ...) with a history that grows frame by frame.
TEST(ViewRun, ASpikingNetworkRunSendsSpikesAndProbeSeriesOverTime) {
  symb::apps::run::RunOptions o;
  ViewTestReader reader;
  auto result = view_test_run(o, "linda_maze.yaml", 2s, 4, reader);  // 0.5 s of wall clock: several frames
  ASSERT_TRUE(result) << result.error();
  ASSERT_TRUE(reader.upgraded());
  const auto spikes = reader.frames("spikes", "\"dots\":[");
  ASSERT_FALSE(spikes.empty()) << reader.size() << " frames";
  std::size_t dots = 0;
  double last = 0;
  for (const auto& f : spikes) {
    const auto d = view_test_numbers(f, "dots");
    ASSERT_EQ(d.size() % 2, 0u);
    for (std::size_t k = 0; k < d.size(); k += 2) {
      EXPECT_GE(d[k], 0);
      EXPECT_LE(d[k], 2.0) << "spike times are the run's seconds";
      EXPECT_GE(d[k + 1], 0) << "a neuron";
      last = std::max(last, d[k]);
    }
    dots += d.size() / 2;
  }
  EXPECT_GT(dots, 100u) << "a spiking network fires";
  EXPECT_GT(last, 1.0) << "spikes keep coming through the run";
  // The rate series: points in more than one frame, each frame's after the one before.
  const auto rates = reader.frames("probes", "\"channel\":\"rate\"");
  std::size_t with_points = 0;
  double before = -1;
  for (const auto& f : rates) {
    const auto p = view_test_numbers(f.substr(f.find("\"channel\":\"rate\"")), "points");
    if (f.find("\"full\":true") != std::string::npos) before = -1;  // all again: the page starts over
    if (p.empty()) continue;
    ++with_points;
    EXPECT_GT(p[0], before) << "new points only";
    before = p[p.size() - 2];
  }
  EXPECT_GE(with_points, 2u) << rates.size() << " probe frames with the rate";
}

// A 3D organism (the caterpillar's five docked modules): the page gets their shapes, their poses
// frame by frame with the hinges waving, the docked pairs, a module's task graph and probes; the
// run is the same as without the view, bit for bit.
TEST(ViewRun, AnOrganismIsShownInThreeDimensionsAndRunsTheSame) {
  symb::apps::run::RunOptions o;
  ViewTestReader reader;
  auto result = view_test_run(o, "caterpillar.yaml", 1s, 2, reader);  // 0.5 s of wall clock: ten poses frames
  ASSERT_TRUE(result) << result.error();
  ASSERT_TRUE(reader.upgraded());
  EXPECT_EQ(reader.frames("hello", "\"world\":{\"kind\":\"organism\",\"modules\":[{\"name\":\"m0\",\"size\":[").size(),
            1u);
  const auto poses = reader.frames("organism");
  ASSERT_GE(poses.size(), 3u) << reader.size() << " frames";
  const auto first = view_test_numbers(poses.front(), "m");
  ASSERT_EQ(first.size(), 5u * 8u) << poses.front();
  double hinge_change = 0;  // the most any hinge moved from its first angle
  for (const auto& f : poses) {
    const auto m = view_test_numbers(f, "m");
    ASSERT_EQ(m.size(), first.size()) << f;
    for (std::size_t k = 0; k < 5; ++k)
      hinge_change = std::max(hinge_change, std::abs(m[8 * k + 7] - first[8 * k + 7]));
  }
  EXPECT_GT(hinge_change, 0.1) << "the hinges wave (amplitude 0.6 rad)";
  // The chain's four docked pairs, each once, the first m0.back (connector 1) to m1.front (0).
  const std::string& end = poses.back();
  const std::string docked = end.substr(end.find("\"docked\":"));
  EXPECT_EQ(std::count(docked.begin(), docked.end(), '['), 5) << docked;
  EXPECT_NE(docked.find("[0,1,1,0]"), std::string::npos) << docked;
  EXPECT_FALSE(reader.frames("graph", "{\"name\":\"osc\",\"type\":\"oscillator\"").empty());
  EXPECT_FALSE(reader.frames("probes", "\"channel\":\"oscillator\"").empty());
  EXPECT_FALSE(reader.frames("status", "\"finished\":true").empty());
  expect_the_run_without_the_view(o, *result);
}

// `symb board --view`: a board has a robot's node and no world. The page gets the board's task
// graph (its link tasks and the scenario's controller), a null world, and a shell on the board's
// node. The link is silent (no simulator): the board runs anyway.
TEST(ViewBoard, ABoardIsShownWithItsTasksAndNoWorld) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("symb_view_board_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  symb::test_support::SymbChild link(SYMB_BINARY, "link --dir '" + (dir / "tty").string() + "'", dir / "link.log");
  symb::testing::eventually([&] { return fs::exists(dir / "tty" / "shell"); });
  ASSERT_TRUE(fs::exists(dir / "tty" / "board")) << link.output();
  symb::test_support::SymbChild board(SYMB_BINARY,
                                      "board '" + std::string(SYMB_SCENARIO_DIR) + "/maze.yaml' --serial '" +
                                          (dir / "tty" / "board").string() + "' --view 0 --duration 20s --quiet",
                                      dir / "board.log");
  std::string out;
  symb::testing::eventually([&] { return (out = board.output()).find("?token=") != std::string::npos; });
  ViewTestReader reader;
  reader.on_notice(out);
  ASSERT_TRUE(reader.upgraded()) << out;
  ASSERT_TRUE(reader.client().send_text("shell tasks"));
  // Stopped with Ctrl-C once its shell has answered the page, not by a short --duration: a busy box
  // may keep this test or the board off its core for seconds between the notice and the answer.
  // Graph frames come from the board's loop, where Ctrl-C is a request to stop, not a kill.
  symb::testing::eventually([&] {
    return !reader.frames("shell", "controller").empty() &&
           !reader.frames("graph", "{\"name\":\"controller\",").empty();
  });
  board.interrupt();
  EXPECT_EQ(board.wait(), 0) << board.output();
  reader.join();
  link.interrupt();
  link.wait();
  fs::remove_all(dir);
  EXPECT_EQ(reader.frames("hello", "\"world\":null").size(), 1u) << reader.size() << " frames";
  EXPECT_TRUE(reader.frames("step").empty()) << "no world, no poses";
  EXPECT_FALSE(reader.frames("graph", "{\"name\":\"controller\",").empty());
  EXPECT_FALSE(reader.frames("graph", "{\"name\":\"ir\",").empty());
  EXPECT_FALSE(reader.frames("shell", "controller").empty()) << "the page's shell runs on the board's node";
  EXPECT_FALSE(reader.frames("status", "\"virtual\":false").empty());
}

}  // namespace
