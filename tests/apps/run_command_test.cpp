// `symb run` as a person runs it, through the binary as a child process: Ctrl-C in the middle of a
// run writes what was run (whole CSV rows, the summary saying where it stopped, the pictures), and
// a command shell on stdio fed from a pipe runs every line it was given.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "symb/apps/run/scenario_run.hpp"
#include "symb/sim/scenario.hpp"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

const std::string kMaze = std::string(SYMB_SCENARIO_DIR) + "/maze.yaml";
const std::string kSubsumption = std::string(SYMB_SCENARIO_DIR) + "/subsumption.yaml";

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

fs::path scratch(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("symb_run_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  return p;
}

std::size_t count(const std::string& text, char c) {
  std::size_t n = 0;
  for (char x : text) n += x == c ? 1 : 0;
  return n;
}

TEST(RunCommand, CtrlCWritesWhatWasRun) {
  const fs::path out = scratch("interrupt");
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1);
    ::dup2(null, 2);
    // Paced, so that there is a middle to interrupt: 10 min simulated would take 12 s.
    // A controller that publishes probes, so that their pictures are written too.
    ::execl(SYMB_BINARY, SYMB_BINARY, "run", kSubsumption.c_str(), "--out", out.c_str(), "--duration", "10min",
            "--speed", "50", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  // Interrupt once a few hundred rows are on disk (what is asserted below: rows were written).
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (count(read(out / "steps.csv"), '\n') < 300 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(10ms);
  ASSERT_GE(count(read(out / "steps.csv"), '\n'), 300u);
  ::kill(pid, SIGINT);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "the run died of its signal instead of stopping";
  EXPECT_EQ(WEXITSTATUS(status), 130);

  const std::string summary = read(out / "summary.txt");
  EXPECT_NE(summary.find("interrupted: at "), std::string::npos) << summary;
  EXPECT_NE(summary.find(" s of 600.00 s"), std::string::npos) << summary;
  EXPECT_NE(summary.find("trajectory hash: "), std::string::npos);
  EXPECT_NE(read(out / "trajectory.svg").find("</svg>"), std::string::npos);
  EXPECT_TRUE(fs::exists(out / "syslog.txt"));
  EXPECT_GT(count(read(out / "probes.csv"), '\n'), 1u);
  std::size_t pictures = 0;
  if (fs::is_directory(out / "probes"))
    for (const auto& e : fs::directory_iterator(out / "probes")) pictures += e.path().extension() == ".svg" ? 1 : 0;
  EXPECT_GT(pictures, 0u) << "no probe pictures";

  // Every row whole: the same number of fields as the header, and the file ends with a newline.
  const std::string csv = read(out / "steps.csv");
  ASSERT_FALSE(csv.empty());
  EXPECT_EQ(csv.back(), '\n');
  std::istringstream rows(csv);
  std::string header, row;
  std::getline(rows, header);
  const std::size_t fields = count(header, ',');
  std::size_t n = 0;
  while (std::getline(rows, row)) {
    ASSERT_EQ(count(row, ','), fields) << "row " << n + 2 << ": " << row;
    ++n;
  }
  EXPECT_GE(n, 299u);
  fs::remove_all(out);
}

// A script piped into a stdio shell: every line runs (the last one has no newline), the replies
// come out on stdout, the end of input is reported, and the run goes on to its end.
TEST(RunCommand, StdioShellFromAPipeRunsEveryLine) {
  const fs::path out = scratch("stdio");
  fs::create_directories(out);
  const fs::path script = out / "script.symb";
  {
    std::ofstream s(script, std::ios::binary);
    s << "tasks\nsuspend controller\ntime";
  }
  const std::string bin = SYMB_BINARY;
  const std::string command = "'" + bin + "' run '" + kMaze + "' --shell stdio --duration 3s --speed 10 --out '" +
                              (out / "run").string() + "' < '" + script.string() + "' > '" +
                              (out / "stdout.txt").string() + "' 2> '" + (out / "stderr.txt").string() + "'";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << read(out / "stderr.txt");
  const std::string replies = read(out / "stdout.txt");
  EXPECT_NE(replies.find("controller"), std::string::npos) << replies;  // `tasks`
  EXPECT_NE(replies.find("suspended"), std::string::npos) << replies;   // `suspend controller`
  EXPECT_NE(replies.find("TIME"), std::string::npos) << replies;        // `time`, without its newline
  EXPECT_NE(read(out / "stderr.txt").find("shell: the session ended"), std::string::npos) << read(out / "stderr.txt");
  EXPECT_NE(read(out / "run" / "syslog.txt").find("end of input: the session ends"), std::string::npos);
  // The run went on to its end after the input ended.
  EXPECT_NE(read(out / "run" / "summary.txt").find("simulated: 3.00 s"), std::string::npos)
      << read(out / "run" / "summary.txt");
  fs::remove_all(out);
}

// One limit for a run's length: a scenario's `duration` and `symb run --duration` both stop at
// sim::kMaxRunDuration (168 h), and both take it exactly.
TEST(RunCommand, ScenarioAndCommandLineShareTheDurationLimit) {
  std::string maze = read(kMaze);
  const auto with = [&](const std::string& d) {
    std::string text = maze;
    const auto at = text.find("\nduration: 10min");
    EXPECT_NE(at, std::string::npos);
    return text.replace(at, 16, "\nduration: " + d);
  };
  EXPECT_TRUE(symb::sim::parse_scenario(with("168h"), "t.yaml").ok());
  auto longer = symb::sim::parse_scenario(with("168.001h"), "t.yaml");
  ASSERT_FALSE(longer.ok());
  EXPECT_NE(longer.error().find("t.yaml:9:11: duration must be between 1ms and 604800s"), std::string::npos)
      << longer.error();

  const std::string bin = SYMB_BINARY;
  const fs::path err = scratch("duration_err");
  const auto run = [&](const std::string& duration) {
    // --csv-every 0 is refused after --duration is read: exit 2 either way, and the message says
    // which option it was.
    const int status = std::system(("'" + bin + "' run '" + kMaze + "' --duration " + duration +
                                    " --csv-every 0 >/dev/null 2>'" + err.string() + "'")
                                       .c_str());
    EXPECT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 2);
    return read(err);
  };
  EXPECT_EQ(run("168h").find("--duration"), std::string::npos) << read(err);
  EXPECT_NE(run("169h").find("--duration"), std::string::npos) << read(err);
  fs::remove(err);
}

// Every shipped scenario starts without a warning about a task it does not define (the
// obstacle-avoidance program once started an 'obstacle_logger' no scenario had).
TEST(RunCommand, ShippedScenariosNameOnlyTheirOwnTasks) {
  std::size_t scenarios = 0;
  for (const auto& e : fs::directory_iterator(SYMB_SCENARIO_DIR)) {
    if (e.path().extension() != ".yaml") continue;
    ++scenarios;
    symb::apps::run::RunOptions o;
    o.scenario_path = e.path().string();
    o.duration = std::chrono::seconds(2);
    o.out_dir = scratch("shipped_" + e.path().stem().string());
    auto r = symb::apps::run::run_scenario(o);
    ASSERT_TRUE(r.ok()) << e.path() << ": " << r.error();
    const std::string log = read(*o.out_dir / "syslog.txt");
    EXPECT_EQ(log.find("no task named"), std::string::npos) << e.path() << "\n" << log;
    fs::remove_all(*o.out_dir);
  }
  EXPECT_GE(scenarios, 10u);
}

}  // namespace
