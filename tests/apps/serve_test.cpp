// `symb serve`: nodes in processes of their own, joined over the DDS bus. Two and four processes
// in a ring of CPG oscillators (each sends [id, phase] to the next at every 20 ms tick) exchange
// hook traffic whose books close across the processes exactly; a process killed mid-run is
// reported by the others, which go on. Release build only: the bus's threads are checked under
// the sanitizers by tests/io/dds_bus_test.cpp, in process.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "support/symb_child.hpp"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

// One line of a serve report's hook table.
struct ServeHookRow {
  std::string sender, receiver, state;
  std::uint64_t attempted = 0, delivered = 0, dropped = 0, in_flight = 0, written = 0, received = 0, lost = 0;
};

struct ServeReport {
  std::string text;
  std::map<std::string, ServeHookRow> hooks;  // by "sender>receiver"
  std::uint64_t peers_lost = 0;
};

ServeReport parse_report(std::string text) {
  ServeReport r;
  r.text = std::move(text);
  static const std::regex row(
      R"(^\d+  (\S+) -> (\S+)  \S+  -?\d+  (up|down)  (\d+)  (\d+)  (\d+)  (\d+)  (\d+)  (\d+)  (\d+).*$)");
  static const std::regex counts(R"(peers lost (\d+))");
  std::istringstream in(r.text);
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (std::regex_match(line, m, row)) {
      ServeHookRow h{m[1], m[2], m[3]};
      std::uint64_t* f[] = {&h.attempted, &h.delivered, &h.dropped, &h.in_flight, &h.written, &h.received, &h.lost};
      for (int i = 0; i < 7; ++i) *f[i] = std::stoull(m[4 + i]);
      r.hooks[h.sender + ">" + h.receiver] = h;
    } else if (std::regex_search(line, m, counts)) {
      r.peers_lost = std::stoull(m[1]);
    }
  }
  return r;
}

class ServeRing {
 public:
  // n processes m0..m(n-1); oscillator k hooked to oscillator k+1 (mod n) on port 1.
  ServeRing(int n, std::string_view test, std::string duration, std::string lease = "2s")
      : dir_(fs::temp_directory_path() / unique(test)) {
    fs::create_directories(dir_);
    std::string hooks;
    for (int k = 0; k < n; ++k)
      hooks += " --hook 'm" + std::to_string(k) + "/osc>m" + std::to_string((k + 1) % n) + "/osc:1'";
    const std::string common = " --domain " + std::to_string(10 + ::getpid() % 200) + " --prefix " + unique(test) +
                               " --lease " + lease + " --duration " + duration + " --link-timeout 5s" + hooks;
    for (int k = 0; k < n; ++k) {
      const std::string args = "serve --node m" + std::to_string(k) +
                               " --exec 'create oscillator osc id=" + std::to_string(k) + " coupling=4 --suspended'" +
                               common;
      children_.push_back(std::make_unique<symb::test_support::SymbChild>(SYMB_BINARY, args,
                                                                          dir_ / ("m" + std::to_string(k) + ".txt")));
    }
  }
  ~ServeRing() {
    children_.clear();
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  symb::test_support::SymbChild& child(int k) { return *children_[static_cast<std::size_t>(k)]; }

 private:
  static std::string unique(std::string_view test) {
    return "serve_" + std::string(test) + "_" + std::to_string(::getpid());
  }
  fs::path dir_;
  std::vector<std::unique_ptr<symb::test_support::SymbChild>> children_;
};

// Every hook of the ring, from its sender's report and its receiver's: exact across processes.
void expect_exact_ring(const std::vector<ServeReport>& reports) {
  const int n = static_cast<int>(reports.size());
  for (int k = 0; k < n; ++k) {
    const int next = (k + 1) % n;
    const std::string key = "m" + std::to_string(k) + "/osc>m" + std::to_string(next) + "/osc";
    ASSERT_TRUE(reports[k].hooks.contains(key)) << reports[k].text;
    ASSERT_TRUE(reports[next].hooks.contains(key)) << reports[next].text;
    const ServeHookRow& out = reports[k].hooks.at(key);
    const ServeHookRow& in = reports[next].hooks.at(key);
    EXPECT_GT(out.written, 20u) << key;  // about 50 in 1 s at 20 ms ticks
    EXPECT_EQ(out.written, in.received + in.lost) << key;
    EXPECT_EQ(in.lost, 0u) << key;  // reliable DDS on one machine loses nothing
    // Each end's books close: sent = written + dropped + still queued; taken = delivered + in flight.
    EXPECT_EQ(out.attempted, out.written + out.dropped + out.in_flight) << key;
    EXPECT_EQ(in.received, in.delivered + in.dropped + in.in_flight) << key;
  }
}

std::vector<ServeReport> finish(ServeRing& ring, int n) {
  std::vector<ServeReport> reports;
  for (int k = 0; k < n; ++k) {
    EXPECT_EQ(ring.child(k).wait(), 0) << ring.child(k).output();
    reports.push_back(parse_report(ring.child(k).output()));
  }
  return reports;
}

class Serve : public ::testing::Test {
 protected:
  void SetUp() override {
#ifdef SYMB_SANITIZER
    GTEST_SKIP() << "processes over DDS: release build only";
#endif
  }
};

TEST_F(Serve, TwoProcessesExchangeHookTrafficWithExactBooks) {
  ServeRing ring(2, "two", "1s");
  expect_exact_ring(finish(ring, 2));
}

TEST_F(Serve, FourProcessesExchangeHookTrafficWithExactBooks) {
  ServeRing ring(4, "four", "1s");
  expect_exact_ring(finish(ring, 4));
}

TEST_F(Serve, AProcessKilledMidRunIsReportedAndTheOthersGoOn) {
  // A 200 ms lease: m3 notices within it, m1 within the participant's (three leases), both well
  // before the run's 2 s end.
  ServeRing ring(4, "kill", "2s", "200ms");
  // Killed once linked and under way (its report says linked when its tasks start).
  const auto until = std::chrono::steady_clock::now() + 10s;
  while (ring.child(2).output().find("serve m2: linked") == std::string::npos &&
         std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(10ms);
  std::this_thread::sleep_for(300ms);
  ring.child(2).interrupt();  // m2 dies at once: SIGINT's default action, no goodbye on DDS
  EXPECT_EQ(ring.child(2).wait(), -1);
  std::vector<ServeReport> reports(4);
  for (int k : {0, 1, 3}) {
    EXPECT_EQ(ring.child(k).wait(), 0) << ring.child(k).output();
    reports[k] = parse_report(ring.child(k).output());
  }
  // m3 heard m2 go silent: reported, counted, and its hook is down.
  EXPECT_EQ(reports[3].peers_lost, 1u) << reports[3].text;
  EXPECT_NE(reports[3].text.find("m2/osc>m3/osc:1: its sender is gone"), std::string::npos) << reports[3].text;
  // m1 lost its reader: reported (within the dead participant's lease, three liveliness leases);
  // what it sent after that is counted as dropped (link_down), and its books close.
  EXPECT_NE(reports[1].text.find("m1/osc>m2/osc:1: no reader left"), std::string::npos) << reports[1].text;
  const ServeHookRow& to_dead = reports[1].hooks.at("m1/osc>m2/osc");
  EXPECT_EQ(to_dead.attempted, to_dead.written + to_dead.dropped + to_dead.in_flight);
  // The hooks between survivors went on, exact.
  for (const char* key : {"m3/osc>m0/osc", "m0/osc>m1/osc"}) {
    const int from = key[1] - '0', to = key[8] - '0';
    const ServeHookRow& out = reports[from].hooks.at(key);
    const ServeHookRow& in = reports[to].hooks.at(key);
    EXPECT_GT(out.written, 60u) << key;  // it kept going after m2 died (about 100 in 2 s)
    EXPECT_EQ(out.written, in.received + in.lost) << key;
    EXPECT_EQ(in.lost, 0u) << key;
  }
}

// An oscillator's mean frequency (Hz) over the last `window` seconds of a probes CSV
// (`symb serve --probes`): its phase (value 0 of channel "oscillator", in [0, 2 pi)) unwrapped.
double serve_frequency(const fs::path& csv, const std::string& task, double window) {
  std::vector<std::pair<double, double>> phase;  // time, phase
  std::istringstream in(symb::test_support::read_whole_file(csv));
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> f;
    std::stringstream ls(line);
    for (std::string x; std::getline(ls, x, ',');) f.push_back(x);
    if (f.size() >= 5 && f[2] == task && f[3] == "oscillator") phase.emplace_back(std::stod(f[0]), std::stod(f[4]));
  }
  if (phase.size() < 2) return 0;
  const double end = phase.back().first;
  double turned = 0, from = -1;
  for (std::size_t i = 1; i < phase.size(); ++i) {
    if (phase[i].first < end - window) continue;
    if (from < 0) from = phase[i - 1].first;
    double d = phase[i].second - phase[i - 1].second;
    if (d < -3.14159) d += 2 * 3.14159265358979;
    turned += d;
  }
  return from < 0 ? 0 : turned / (2 * 3.14159265358979) / (end - from);
}

// Two CPG oscillators of different natural frequencies (1.0 and 1.4 Hz), each pulled towards the
// other's phase: they lock at one frequency, about the mean. Split over two processes, with their
// phases over DDS, they lock at the same frequency as in one process, within 0.05 Hz (measured:
// 1.20 Hz both ways); uncoupled they would stay 0.4 Hz apart.
TEST_F(Serve, SplitOverTwoProcessesOscillatorsLockAsInOne) {
  const std::string tag = std::to_string(::getpid());
  const fs::path dir = fs::temp_directory_path() / ("serve_lock_" + tag);
  fs::create_directories(dir);
  const std::string a = "create oscillator osc id=0 frequency=1 coupling=6 --suspended";
  const std::string b = "create oscillator osc id=1 frequency=1.4 coupling=6 --suspended";
  const std::string common = " --domain " + std::to_string(10 + ::getpid() % 200) +
                             " --lease 2s --duration 1200ms --link-timeout 5s --prefix lock" + tag;
  // One process: both oscillators on one node (the second named osc2), hooked locally.
  symb::test_support::SymbChild one(SYMB_BINARY,
                                    "serve --node m0 --exec '" + a + "' --exec '" +
                                        std::regex_replace(b, std::regex("osc id"), "osc2 id") +
                                        "' --exec 'hook osc osc2 --port 1' --exec 'hook osc2 osc --port 1' --probes " +
                                        (dir / "one.csv").string() + common + "_one",
                                    dir / "one.txt");
  // Two processes, at the same time (their own topic prefix).
  const std::string hooks = " --hook 'm0/osc>m1/osc:1' --hook 'm1/osc>m0/osc:1'";
  symb::test_support::SymbChild p0(
      SYMB_BINARY, "serve --node m0 --exec '" + a + "' --probes " + (dir / "p0.csv").string() + common + "_two" + hooks,
      dir / "p0.txt");
  symb::test_support::SymbChild p1(
      SYMB_BINARY, "serve --node m1 --exec '" + b + "' --probes " + (dir / "p1.csv").string() + common + "_two" + hooks,
      dir / "p1.txt");
  ASSERT_EQ(one.wait(), 0) << one.output();
  ASSERT_EQ(p0.wait(), 0) << p0.output();
  ASSERT_EQ(p1.wait(), 0) << p1.output();
  // Over the last 0.6 s of 1.2: the lock takes about 0.2 s.
  const double one_a = serve_frequency(dir / "one.csv", "osc", 0.6);
  const double one_b = serve_frequency(dir / "one.csv", "osc2", 0.6);
  const double two_a = serve_frequency(dir / "p0.csv", "osc", 0.6);
  const double two_b = serve_frequency(dir / "p1.csv", "osc", 0.6);
  std::printf("lock: one process %.4f / %.4f Hz, two processes %.4f / %.4f Hz\n", one_a, one_b, two_a, two_b);
  EXPECT_NEAR(one_a, 1.2, 0.05) << "locked at about the mean of 1.0 and 1.4 Hz";
  EXPECT_NEAR(one_a, one_b, 0.02);
  EXPECT_NEAR(two_a, two_b, 0.02) << "split over processes: locked too";
  EXPECT_NEAR(two_a, one_a, 0.05) << "the same lock as in one process";
  std::error_code ec;
  fs::remove_all(dir, ec);
}

// Two network namespaces joined by a veth pair, as two machines on one cable: the processes find
// each other by DDS discovery with no configuration. Needs root (ip netns); skipped otherwise.
class ServeNamespaces {
 public:
  explicit ServeNamespaces(const std::string& tag) : a_("symb_a_" + tag), b_("symb_b_" + tag) {
    const std::string va = "sva" + tag, vb = "svb" + tag;
    ok_ = std::system(("(ip netns add " + a_ + " && ip netns add " + b_ + " && ip link add " + va +
                       " type veth peer name " + vb + " && ip link set " + va + " netns " + a_ + " && ip link set " +
                       vb + " netns " + b_ + " && ip -n " + a_ + " addr add 10.77.0.1/24 dev " + va + " && ip -n " +
                       b_ + " addr add 10.77.0.2/24 dev " + vb + " && ip -n " + a_ + " link set " + va +
                       " up && ip -n " + b_ + " link set " + vb + " up && ip -n " + a_ + " link set lo up && ip -n " +
                       b_ + " link set lo up) > /dev/null 2>&1")
                          .c_str()) == 0;
  }
  ~ServeNamespaces() {
    (void)std::system(("ip netns del " + a_ + " > /dev/null 2>&1; ip netns del " + b_ + " > /dev/null 2>&1").c_str());
  }
  bool ok() const { return ok_; }
  const std::string& a() const { return a_; }
  const std::string& b() const { return b_; }

 private:
  std::string a_, b_;
  bool ok_ = false;
};

TEST_F(Serve, TwoNetworkNamespacesFindEachOtherWithNoConfiguration) {
  if (::geteuid() != 0) GTEST_SKIP() << "ip netns needs root";
  // Short names: interface names have at most 15 characters.
  const std::string tag = std::to_string(::getpid() % 100000);
  ServeNamespaces ns(tag);
  if (!ns.ok()) GTEST_SKIP() << "this machine does not allow network namespaces with a veth pair";
  const fs::path dir = fs::temp_directory_path() / ("serve_netns_" + tag);
  fs::create_directories(dir);
  const std::string common = " --domain 3 --prefix netns" + tag +
                             " --lease 2s --duration 1s --link-timeout 5s --hook 'm0/osc>m1/osc:1' --hook "
                             "'m1/osc>m0/osc:1'";
  std::vector<std::unique_ptr<symb::test_support::SymbChild>> children;
  for (int k = 0; k < 2; ++k)
    children.push_back(std::make_unique<symb::test_support::SymbChild>(
        "/usr/sbin/ip",
        "netns exec " + (k == 0 ? ns.a() : ns.b()) + " " + SYMB_BINARY + " serve --node m" + std::to_string(k) +
            " --exec 'create oscillator osc id=" + std::to_string(k) + " coupling=4 --suspended'" + common,
        dir / ("m" + std::to_string(k) + ".txt")));
  std::vector<ServeReport> reports;
  for (auto& c : children) {
    EXPECT_EQ(c->wait(), 0) << c->output();
    reports.push_back(parse_report(c->output()));
  }
  EXPECT_NE(reports[0].text.find("serve m0: linked"), std::string::npos) << reports[0].text;
  expect_exact_ring(reports);
  std::error_code ec;
  fs::remove_all(dir, ec);
}

}  // namespace
