// The Cortex-M board image (board/, docs/board.md) under QEMU's mps2-an385 in hardware in the
// loop, driven by the real `symb sim` over the emulated UART0 (a pseudo-terminal), with its shell
// on UART1 (`symb shell --serial`). Checked:
//  - the maze with zero contacts, and the wheel commands step by step equal to the Linux
//    `symb board` run of the same seed (both beside `symb run`, the in-process run); steps may
//    part only after a late answer (a loaded machine: docs/hil.md), which the test reports;
//  - the image's own figures at the end: no heap allocation on the message path while frames
//    came, RAM (static + stack + heap high-water) within 32 KiB, QEMU's exit code 0;
//  - the shell lists the tasks, suspends the controller (the wheels' watchdog stops the robot) and
//    resumes it (the robot drives again), and answers malformed lines with errors, not silence;
//  - corrupted frames written onto the UART are counted exactly, and the board keeps answering.
// Release build only; about 20 s of wall clock in all.
#include <fcntl.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/io/frame_codec.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/sim/hil_protocol.hpp"

#include "support/symb_child.hpp"

#ifdef SYMB_BOARD_ELF

namespace board_qemu_test {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using symb::test_support::read_whole_file;
using symb::test_support::SymbChild;

const std::string kMaze = std::string(SYMB_SCENARIO_DIR) + "/maze.yaml";

struct Row {
  double x, y, left, right;
  bool contact;
};

std::vector<Row> rows_of(const fs::path& csv) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  std::vector<Row> out;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream s(line);
    for (std::string cell; std::getline(s, cell, ',');) f.push_back(cell);
    if (f.size() < 15) continue;
    out.push_back({std::stod(f[2]), std::stod(f[3]), std::stod(f[12]), std::stod(f[13]), f[14] == "1"});
  }
  return out;
}

// "key=value" numbers of the line that starts with `prefix`.
std::map<std::string, long long> key_values(const std::string& text, const std::string& prefix) {
  std::map<std::string, long long> out;
  const auto at = text.find(prefix);
  if (at == std::string::npos) return out;
  std::stringstream s(text.substr(at, text.find('\n', at) - at));
  for (std::string kv; s >> kv;)
    if (auto eq = kv.find('='); eq != std::string::npos) out[kv.substr(0, eq)] = std::stoll(kv.substr(eq + 1));
  return out;
}

// "applied N (L late)" of `symb sim`'s output: the late answers.
long long late_answers(const std::string& sim_output) {
  std::smatch m;
  return std::regex_search(sim_output, m, std::regex(R"(\((\d+) late\))")) ? std::stoll(m[1]) : -1;
}

// The board image in QEMU, its UARTs on pseudo-terminals.
class QemuBoard {
 public:
  QemuBoard(const fs::path& dir, const std::string& append)
      : child_(SYMB_QEMU_ARM,
               "-machine mps2-an385 -cpu cortex-m3 -display none -monitor none -semihosting-config "
               "enable=on,target=native -serial pty -serial pty -kernel '" SYMB_BOARD_ELF "' -append '" +
                   append + "'",
               dir / "qemu.log") {
    // QEMU names the terminals, then the image says it runs.
    for (int i = 0; i < 500 && child_.output().find(" tasks;") == std::string::npos; ++i)
      std::this_thread::sleep_for(10ms);
    std::smatch m;
    const std::string out = child_.output();
    const std::regex pty(R"((/dev/pts/\d+) \(label serial(\d)\))");
    for (auto it = std::sregex_iterator(out.begin(), out.end(), pty); it != std::sregex_iterator(); ++it)
      ((*it)[2] == "0" ? data : shell) = (*it)[1];
    // QEMU looks for a reader on a pseudo-terminal once a second and keeps or drops what passes
    // meanwhile: hold both lines open from the start, as a person's terminals would be, so the
    // simulator's handshake frames do not arrive in a burst a second late (a late answer).
    for (const std::string* p : {&data, &shell})
      if (!p->empty()) keepers_.push_back(::open(p->c_str(), O_WRONLY | O_NOCTTY));
    std::this_thread::sleep_for(1100ms);
  }
  ~QemuBoard() {
    for (int fd : keepers_)
      if (fd >= 0) ::close(fd);
  }
  int wait() { return child_.wait(); }
  std::string output() const { return child_.output(); }
  std::string data, shell;

 private:
  SymbChild child_;
  std::vector<int> keepers_;
};

class BoardQemu : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::string(SYMB_QEMU_ARM).empty()) GTEST_SKIP() << "qemu-system-arm not found (scripts/setup installs it)";
    if (!fs::exists(SYMB_BOARD_ELF)) GTEST_SKIP() << SYMB_BOARD_ELF << " was not built (gcc-arm-none-eabi missing?)";
    dir_ = fs::temp_directory_path() / ("symb-board-qemu-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure() && !dir_.empty()) fs::remove_all(dir_);
  }
  fs::path dir_;
};

TEST_F(BoardQemu, DrivesTheMazeStepByStepAsTheLinuxBoard) {
  constexpr int kSeconds = 6;
  // The Linux board at the same time, over `symb link`'s pseudo-terminals.
  SymbChild link(SYMB_BINARY, "link --dir '" + (dir_ / "tty").string() + "'", dir_ / "link.log");
  for (int i = 0; i < 200 && !fs::exists(dir_ / "tty" / "shell"); ++i) std::this_thread::sleep_for(20ms);
  SymbChild linux_board(SYMB_BINARY, "board '" + kMaze + "' --serial '" + (dir_ / "tty" / "board").string() + "'",
                        dir_ / "board.log");
  for (int i = 0; i < 500 && linux_board.output().find("Ctrl-C to stop") == std::string::npos; ++i)
    std::this_thread::sleep_for(10ms);
  // The QEMU board last, just before the simulators: its run (--duration, seconds of its own
  // clock, after which it prints its statistics and exits) must outlast the simulator's, and
  // started first it also spent the others' start-up, which took about 4.5 s in one fresh clone's CI
  // run: the board left 1.5 s before the end of the simulated run.
  QemuBoard qemu(dir_, "--duration " + std::to_string(kSeconds + 4));
  ASSERT_FALSE(qemu.data.empty()) << qemu.output();
  const std::string duration = " --duration " + std::to_string(kSeconds) + "s";
  SymbChild sim_qemu(
      SYMB_BINARY, "sim '" + kMaze + "' --serial " + qemu.data + duration + " --out '" + (dir_ / "qemu").string() + "'",
      dir_ / "sim-qemu.log");
  SymbChild sim_linux(SYMB_BINARY,
                      "sim '" + kMaze + "' --serial '" + (dir_ / "tty" / "sim").string() + "'" + duration + " --out '" +
                          (dir_ / "linux").string() + "'",
                      dir_ / "sim-linux.log");
  ASSERT_EQ(sim_qemu.wait(), 0) << sim_qemu.output();
  ASSERT_EQ(sim_linux.wait(), 0) << sim_linux.output();
  SymbChild run(SYMB_BINARY, "run '" + kMaze + "'" + duration + " --out '" + (dir_ / "run").string() + "'",
                dir_ / "run.log");
  ASSERT_EQ(run.wait(), 0) << run.output();
  linux_board.interrupt();
  EXPECT_EQ(linux_board.wait(), 0) << linux_board.output();
  link.interrupt();
  link.wait();
  ASSERT_EQ(qemu.wait(), 0) << qemu.output();

  const auto on_qemu = rows_of(dir_ / "qemu" / "steps.csv");
  const auto on_linux = rows_of(dir_ / "linux" / "steps.csv");
  const auto in_process = rows_of(dir_ / "run" / "steps.csv");
  ASSERT_EQ(on_qemu.size(), static_cast<std::size_t>(kSeconds * 1000 / 30)) << sim_qemu.output();
  ASSERT_EQ(on_linux.size(), on_qemu.size());
  std::size_t contacts = 0, same_as_linux = 0, same_as_run = 0, first_difference = on_qemu.size();
  double travelled = 0;
  for (std::size_t i = 0; i < on_qemu.size(); ++i) {
    contacts += on_qemu[i].contact ? 1 : 0;
    if (i > 0) travelled += std::hypot(on_qemu[i].x - on_qemu[i - 1].x, on_qemu[i].y - on_qemu[i - 1].y);
    const bool same = on_qemu[i].left == on_linux[i].left && on_qemu[i].right == on_linux[i].right;
    same_as_linux += same ? 1 : 0;
    if (!same && first_difference == on_qemu.size()) first_difference = i;
    same_as_run += on_qemu[i].left == in_process[i].left && on_qemu[i].right == in_process[i].right ? 1 : 0;
  }
  const long long late_qemu = late_answers(sim_qemu.output()), late_linux = late_answers(sim_linux.output());
  std::printf(
      "board on QEMU: %.1f cm in %d s, %zu contacts; wheel commands equal to the Linux board's in %zu of %zu "
      "steps (first difference at step %zu), to the in-process run's in %zu; late answers: QEMU %lld, "
      "Linux %lld\n",
      travelled, kSeconds, contacts, same_as_linux, on_qemu.size(), first_difference, same_as_run, late_qemu,
      late_linux);
  EXPECT_EQ(contacts, 0u);
  EXPECT_GT(travelled, 40.0);  // 10 s drive 99 cm (measured); 6 s at least 40
  // Step for step, unless an answer came late (a loaded machine: that step runs on the previous
  // command, docs/hil.md, and the runs may part from there on). The QEMU board against the
  // in-process run needs only its own answers on time; against the Linux board, both boards'.
  if (late_qemu == 0) {
    EXPECT_EQ(same_as_run, on_qemu.size()) << "QEMU's answers were all on time";
  }
  if (late_qemu == 0 && late_linux == 0) {
    EXPECT_EQ(same_as_linux, on_qemu.size()) << "all answers were on time";
  }
  if (same_as_linux < on_qemu.size()) {
    EXPECT_GT(late_qemu + late_linux, 0) << "the runs parted without a late answer";
  }
  const auto stats = key_values(qemu.output(), "board-stats:");
  ASSERT_FALSE(stats.empty()) << qemu.output();
  EXPECT_EQ(stats.at("bad"), 0);
  EXPECT_GE(stats.at("good"), static_cast<long long>(on_qemu.size()));
  EXPECT_EQ(stats.at("heap_allocs_in_run"), 0) << "the message path allocated";
  EXPECT_LE(stats.at("ram_maze"), 32 * 1024);
  EXPECT_LE(stats.at("ram"), 32 * 1024);  // no shell commands here
}

// Writes `lines` to `symb shell --serial PTY` from a pipe; its output.
std::string shell_session(const fs::path& dir, const std::string& pty, const std::string& name,
                          const std::string& lines) {
  const fs::path in = dir / (name + ".in");
  std::ofstream(in) << lines;
  SymbChild shell(SYMB_BINARY, "shell --serial " + pty + " < '" + in.string() + "'", dir / (name + ".log"));
  shell.wait();
  return shell.output();
}

// Frames the board's decoder refuses: good IR frames with one data byte changed by the HIL
// injector (sim::corrupt_frame, as `symb link --corrupt` does), so no delimiter is made or lost and
// the simulator's frames around them stay whole.
void write_corrupted_frames(const std::string& pty, int n) {
  const int fd = ::open(pty.c_str(), O_WRONLY | O_NOCTTY);
  ASSERT_GE(fd, 0) << pty;
  symb::kernel::RandomStream random(5);
  for (int i = 0; i < n; ++i) {
    symb::sim::HilIrFrame f;
    f.seq = 999'999;
    std::vector<std::byte> frame = symb::io::encode_frame(symb::sim::encode_ir_payload(f));
    ASSERT_TRUE(symb::sim::corrupt_frame(frame, random));
    ASSERT_EQ(::write(fd, frame.data(), frame.size()), static_cast<ssize_t>(frame.size()));
    std::this_thread::sleep_for(50ms);
  }
  ::close(fd);
}

TEST_F(BoardQemu, ShellSuspendsAndResumesTheControllerSurvivesBadLinesAndBadFramesAreCounted) {
  QemuBoard qemu(dir_, "--duration 12");
  ASSERT_FALSE(qemu.shell.empty()) << qemu.output();
  SymbChild sim(SYMB_BINARY,
                "sim '" + kMaze + "' --serial " + qemu.data + " --duration 8s --out '" + (dir_ / "sim").string() + "'",
                dir_ / "sim.log");
  for (int i = 0; i < 300 && sim.output().find("board answered") == std::string::npos; ++i)
    std::this_thread::sleep_for(10ms);
  // The board takes its maze-graph RAM figure at the 20th frame, before any shell command.
  std::this_thread::sleep_for(1s);

  const std::string listed = shell_session(dir_, qemu.shell, "tasks", "tasks\n");
  for (const char* task : {"link", "ir", "controller", "wheels"})
    EXPECT_NE(listed.find(task), std::string::npos) << task << " not listed:\n" << listed;

  std::this_thread::sleep_for(500ms);
  const std::string suspended = shell_session(dir_, qemu.shell, "suspend", "suspend controller\n");
  EXPECT_EQ(suspended.find("error"), std::string::npos) << suspended;
  std::this_thread::sleep_for(1500ms);
  const std::string resumed = shell_session(dir_, qemu.shell, "resume", "resume controller\n");
  EXPECT_EQ(resumed.find("error"), std::string::npos) << resumed;

  // Malformed lines: an unknown command, a missing argument, control bytes, a very long line;
  // each answered with an error, and the shell still answers afterwards.
  const std::string bad = shell_session(dir_, qemu.shell, "bad",
                                        "frobnicate\nsuspend\n\x01\x02\x7f((\n" + std::string(600, 'x') + "\ntasks\n");
  EXPECT_NE(bad.find("error"), std::string::npos) << bad;
  EXPECT_NE(bad.find("controller"), std::string::npos) << "no answer after the malformed lines:\n" << bad;

  constexpr int kCorrupted = 5;
  write_corrupted_frames(qemu.data, kCorrupted);
  ASSERT_EQ(sim.wait(), 0) << sim.output();
  ASSERT_EQ(qemu.wait(), 0) << qemu.output();

  // While suspended the watchdog stopped the wheels; after resume the robot drove on.
  const auto rows = rows_of(dir_ / "sim" / "steps.csv");
  std::size_t stopped = 0, moving_after = 0, stop_step = 0;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    if (rows[i].left == 0 && rows[i].right == 0 && i > 10) {
      ++stopped;
      stop_step = i;
    }
    if (stopped > 0 && i > stop_step && (rows[i].left != 0 || rows[i].right != 0)) ++moving_after;
  }
  std::printf("board on QEMU: %zu steps stopped while the controller was suspended, %zu moving after the resume\n",
              stopped, moving_after);
  EXPECT_GE(stopped, 20u);       // 1.5 s suspended: about 48 steps, less the watchdog's 45 ms and the shell's
  EXPECT_GE(moving_after, 20u);  // the rest of the run
  const auto stats = key_values(qemu.output(), "board-stats:");
  ASSERT_FALSE(stats.empty()) << qemu.output();
  // Each one bad (a CRC error, or a bad version when the version byte was hit), nothing else.
  EXPECT_EQ(stats.at("bad"), kCorrupted) << qemu.output();
  EXPECT_LE(stats.at("crc"), kCorrupted);
  EXPECT_GE(stats.at("watchdog"), 1);
  EXPECT_GE(stats.at("good"), 250);  // 8 s of frames, every one taken
  EXPECT_LE(stats.at("ram_maze"), 32 * 1024);
  std::printf("board on QEMU: RAM %lld bytes for the maze graph, %lld at most with the shell's replies\n",
              stats.at("ram_maze"), stats.at("ram"));
}

}  // namespace board_qemu_test

#endif  // SYMB_BOARD_ELF
