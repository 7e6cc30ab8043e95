// What `symb run` records per step, and how it scales (issue 17): steps.h5 holds exactly the poses
// the run produced and reads back through the HDF5 C API (and h5py), decimation keeps exactly
// every N-th step of the chosen robots, a run stopped early leaves a closed, readable file with
// every step so far, steps.csv's text is byte for byte printf's, bad option values get errors that
// name them, and a crowd's pictures (density map, sampled trails, per-robot histograms) hold what
// they should.
#include <fcntl.h>
#include <hdf5.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/apps/run/crowd_pictures.hpp"
#include "symb/apps/run/record_options.hpp"
#include "symb/apps/run/run_recording.hpp"
#include "symb/apps/run/scenario_run.hpp"
#include "symb/apps/run/steps_csv.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/scenario_session.hpp"

#include "support/measured.hpp"
#include "support/symb_child.hpp"

namespace symb::apps::run {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

const std::string kSwarm = std::string(SYMB_SCENARIO_DIR) + "/swarm.yaml";

std::string read_text(const fs::path& p) { return test_support::read_whole_file(p); }

fs::path scratch_dir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("symb_rec_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  return p;
}

std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size())) ++n;
  return n;
}

// steps.h5 read back through the HDF5 C API.
class H5File {
 public:
  explicit H5File(const fs::path& p) : id_(H5Fopen(p.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT)) {}
  ~H5File() {
    if (id_ >= 0) H5Fclose(id_);
  }
  bool ok() const { return id_ >= 0; }

  std::vector<hsize_t> dims(const char* name) const {
    const hid_t set = H5Dopen2(id_, name, H5P_DEFAULT);
    const hid_t space = H5Dget_space(set);
    std::vector<hsize_t> d(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space)));
    H5Sget_simple_extent_dims(space, d.data(), nullptr);
    H5Sclose(space);
    H5Dclose(set);
    return d;
  }
  template <class T>
  std::vector<T> read(const char* name, hid_t type) const {
    std::size_t n = 1;
    for (hsize_t d : dims(name)) n *= d;
    std::vector<T> v(n);
    const hid_t set = H5Dopen2(id_, name, H5P_DEFAULT);
    if (n > 0) H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    H5Dclose(set);
    return v;
  }
  std::vector<std::string> strings(const char* name) const {
    const hid_t set = H5Dopen2(id_, name, H5P_DEFAULT);
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, H5T_VARIABLE);
    H5Tset_cset(type, H5T_CSET_UTF8);
    std::vector<char*> raw(dims(name)[0]);
    H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, raw.data());
    std::vector<std::string> out(raw.begin(), raw.end());
    const hid_t space = H5Dget_space(set);
    H5Dvlen_reclaim(type, space, H5P_DEFAULT, raw.data());
    H5Sclose(space);
    H5Tclose(type);
    H5Dclose(set);
    return out;
  }
  template <class T>
  T attribute(const char* name, hid_t type) const {
    T v{};
    const hid_t a = H5Aopen(id_, name, H5P_DEFAULT);
    H5Aread(a, type, &v);
    H5Aclose(a);
    return v;
  }
  std::string string_attribute(const char* name) const {
    const hid_t a = H5Aopen(id_, name, H5P_DEFAULT);
    const hid_t type = H5Aget_type(a);
    char* text = nullptr;
    H5Aread(a, type, &text);
    std::string s = text ? text : "";
    H5free_memory(text);
    H5Tclose(type);
    H5Aclose(a);
    return s;
  }

 private:
  hid_t id_;
};

// A 2D session on the virtual-time executor with a RunRecording, and every step's records kept
// aside to compare the files with.
struct RecordedRun {
  std::vector<sim::StepRecord> steps;
  std::vector<std::string> names;
  std::vector<fs::path> files;
  RecordFigures figures;
};

RecordedRun record_run(const std::string& scenario_path, kernel::Duration duration, const RecordOptions& options,
                       std::uint32_t every, const fs::path& dir) {
  RecordedRun out;
  auto scenario = sim::load_scenario(scenario_path);
  EXPECT_TRUE(scenario.ok()) << scenario.error();
  if (!scenario) return out;
  kernel::VirtualTimeExecutor executor;
  auto session = sim::ScenarioSession::create(*scenario, executor);
  EXPECT_TRUE(session.ok()) << session.error();
  if (!session) return out;
  fs::create_directories(dir);
  auto recording = RunRecording::open((*session)->world(), *scenario, (*session)->seed(), options, every, dir);
  EXPECT_TRUE(recording.ok()) << recording.error();
  if (!recording) return out;
  for (std::size_t i = 0; i < (*session)->world().robot_count(); ++i)
    out.names.push_back((*session)->world().robot_name(i));
  (*session)->runner().add_observer([&](const sim::StepRecord& r) {
    (*recording)->recorder().on_step(r);
    out.steps.push_back(r);
  });
  (*session)->start();
  executor.run_until(executor.clock().now() + duration);
  (*session)->stop();
  auto files = (*recording)->finish(scenario->world, "test", (*session)->world().time(), false);
  EXPECT_TRUE(files.ok()) << files.error();
  if (files) out.files = *files;
  out.figures = (*recording)->figures();
  return out;
}

TEST(Recording, Hdf5HoldsExactlyThePosesOfTheRun) {
  const fs::path dir = scratch_dir("exact");
  RecordOptions o;
  o.format = RecordFormat::kHdf5;
  const RecordedRun run = record_run(kSwarm, 3s, o, 1, dir);
  ASSERT_EQ(run.steps.size(), 100u);
  const std::size_t robots = run.names.size();
  ASSERT_EQ(robots, 12u);
  EXPECT_FALSE(fs::exists(dir / "steps.csv"));

  H5File f(dir / "steps.h5");
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f.string_attribute("format"), "symbricator steps 1");
  EXPECT_EQ(f.string_attribute("scenario"), "swarm");
  EXPECT_EQ(f.attribute<std::uint64_t>("seed", H5T_NATIVE_UINT64), 7u);
  EXPECT_DOUBLE_EQ(f.attribute<double>("control_period_s", H5T_NATIVE_DOUBLE), 0.03);
  EXPECT_EQ(f.attribute<std::uint64_t>("robot_count", H5T_NATIVE_UINT64), 12u);
  EXPECT_EQ(f.attribute<std::uint64_t>("steps", H5T_NATIVE_UINT64), 100u);
  EXPECT_EQ(f.attribute<std::uint8_t>("interrupted", H5T_NATIVE_UINT8), 0u);
  EXPECT_EQ(f.strings("robots"), run.names);
  EXPECT_EQ(f.dims("pose"), (std::vector<hsize_t>{100, robots, 3}));
  EXPECT_EQ(f.dims("ir"), (std::vector<hsize_t>{100, robots, 7}));

  const auto step = f.read<std::uint64_t>("step", H5T_NATIVE_UINT64);
  const auto time = f.read<double>("time_s", H5T_NATIVE_DOUBLE);
  const auto pose = f.read<double>("pose", H5T_NATIVE_DOUBLE);
  const auto ir = f.read<float>("ir", H5T_NATIVE_FLOAT);
  const auto wheels = f.read<double>("wheels", H5T_NATIVE_DOUBLE);
  const auto contact = f.read<std::uint8_t>("contact", H5T_NATIVE_UINT8);
  std::size_t moved = 0;
  for (std::size_t t = 0; t < run.steps.size(); ++t) {
    const sim::StepRecord& r = run.steps[t];
    ASSERT_EQ(step[t], r.step);
    EXPECT_DOUBLE_EQ(time[t], static_cast<double>(r.step) * 0.03);
    for (std::size_t i = 0; i < robots; ++i) {
      const sim::RobotState& s = r.robots[i].state;
      const std::size_t k = t * robots + i;
      // Bit for bit: the file is the run.
      ASSERT_EQ(pose[3 * k], s.pose.x) << "step " << t << " robot " << i;
      ASSERT_EQ(pose[3 * k + 1], s.pose.y);
      ASSERT_EQ(pose[3 * k + 2], s.pose.theta);
      ASSERT_EQ(wheels[2 * k], s.left_speed);
      ASSERT_EQ(wheels[2 * k + 1], s.right_speed);
      ASSERT_EQ(contact[k], s.in_contact ? 1 : 0);
      for (std::size_t j = 0; j < 7; ++j)  // rounded to 0.1, as steps.csv rounds them
        ASSERT_EQ(ir[7 * k + j], static_cast<float>(std::nearbyint(static_cast<double>(r.robots[i].ir[j]) * 10) / 10))
            << "step " << t << " robot " << i;
      moved += t > 0 && pose[3 * k] != run.steps[0].robots[i].state.pose.x ? 1 : 0;
    }
  }
  EXPECT_GT(moved, 100u) << "the robots should move";
  // Deflated: 66 154 bytes measured (steps.csv of the same steps: 96 936; raw arrays 82 800, and
  // the metadata and chunk index of a file this small weigh in).
  EXPECT_TRUE(testing::near_measured(static_cast<double>(fs::file_size(dir / "steps.h5")), 66154, 6600));
  fs::remove_all(dir);
}

TEST(Recording, DecimationKeepsEveryNthStepOfTheChosenRobots) {
  const fs::path dir = scratch_dir("every");
  RecordOptions o;
  o.format = RecordFormat::kBoth;
  o.robots = "thymio2..thymio4,thymio9";
  const RecordedRun run = record_run(kSwarm, 3s, o, 7, dir);
  ASSERT_EQ(run.steps.size(), 100u);
  const std::vector<std::size_t> chosen = {2, 3, 4, 9};

  H5File f(dir / "steps.h5");
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f.attribute<std::uint32_t>("record_every", H5T_NATIVE_UINT32), 7u);
  EXPECT_EQ(f.strings("robots"), (std::vector<std::string>{"thymio2", "thymio3", "thymio4", "thymio9"}));
  const auto index = f.read<std::uint32_t>("robot_index", H5T_NATIVE_UINT32);
  EXPECT_EQ(std::vector<std::size_t>(index.begin(), index.end()), chosen);
  const auto step = f.read<std::uint64_t>("step", H5T_NATIVE_UINT64);
  const auto pose = f.read<double>("pose", H5T_NATIVE_DOUBLE);
  // Steps 1, 8, 15, ..., 99: the first, then every 7th.
  ASSERT_EQ(step.size(), 15u);
  ASSERT_EQ(pose.size(), 15u * 4u * 3u);
  for (std::size_t t = 0; t < step.size(); ++t) {
    EXPECT_EQ(step[t], 1 + 7 * t);
    const sim::StepRecord& r = run.steps[7 * t];
    ASSERT_EQ(r.step, step[t]);
    for (std::size_t j = 0; j < chosen.size(); ++j) {
      EXPECT_EQ(pose[(t * 4 + j) * 3], r.robots[chosen[j]].state.pose.x);
      EXPECT_EQ(pose[(t * 4 + j) * 3 + 1], r.robots[chosen[j]].state.pose.y);
    }
  }
  // The CSV holds the same rows: 15 steps x 4 robots, in that order.
  std::istringstream csv(read_text(dir / "steps.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line + "\n", steps_csv_header());
  std::vector<std::string> rows;
  while (std::getline(csv, line)) rows.push_back(line);
  ASSERT_EQ(rows.size(), 60u);
  for (std::size_t t = 0; t < 15; ++t)
    for (std::size_t j = 0; j < 4; ++j) {
      std::string expected;
      append_steps_csv_row(expected, static_cast<double>(1 + 7 * t) * 0.03, run.names[chosen[j]],
                           run.steps[7 * t].robots[chosen[j]]);
      EXPECT_EQ(rows[t * 4 + j] + "\n", expected);
    }
  EXPECT_EQ(run.figures.recorded_steps, 15u);
  EXPECT_EQ(run.figures.recorded_robots, 4u);
  fs::remove_all(dir);
}

// The text of a row is exactly what printf("%.3f" ...) wrote, over values of every size and sign,
// ties included (x.xxx5 is not exact in binary: both round the binary value).
TEST(Recording, CsvRowsAreTheTextPrintfWrote) {
  kernel::RandomStream random(17, 0);
  std::string row;
  char buf[512];
  for (int n = 0; n < 20000; ++n) {
    sim::RobotStep s;
    const double scale = std::pow(10.0, random.uniform(-4, 7));
    s.state.pose = {random.uniform(-1, 1) * scale, random.uniform(-1, 1) * scale, random.uniform(-4, 4)};
    if (n % 7 == 0) s.state.pose.x = std::round(random.uniform(-1e4, 1e4)) / 1000 + 0.0005;
    if (n % 11 == 0) s.state.pose.y = -0.0;
    s.state.left_speed = random.uniform(-20, 20);
    s.state.right_speed = n % 5 == 0 ? 0.0 : random.uniform(-20, 20);
    s.state.in_contact = n % 3 == 0;
    for (float& v : s.ir) v = static_cast<float>(random.uniform(0, 4500));
    row.clear();
    const double t = n * 0.03;
    append_steps_csv_row(row, t, "r" + std::to_string(n), s);
    int len = std::snprintf(buf, sizeof buf, "%.3f,r%d,%.3f,%.3f,%.4f", t, n, s.state.pose.x, s.state.pose.y,
                            s.state.pose.theta);
    std::string expected(buf, static_cast<std::size_t>(len));
    for (float v : s.ir) {
      len = std::snprintf(buf, sizeof buf, ",%.1f", static_cast<double>(v));
      expected.append(buf, static_cast<std::size_t>(len));
    }
    len = std::snprintf(buf, sizeof buf, ",%.3f,%.3f,%d\n", s.state.left_speed, s.state.right_speed,
                        s.state.in_contact ? 1 : 0);
    expected.append(buf, static_cast<std::size_t>(len));
    ASSERT_EQ(row, expected) << "value set " << n;
  }
}

// A run stopped early (what Ctrl-C asks for, here asked by the test after a few slices) leaves a
// closed file with every step run, the last one equal to the run's end.
TEST(Recording, AnInterruptedRunLeavesAReadableFileWithEveryStep) {
  const fs::path dir = scratch_dir("interrupted");
  RunOptions o;
  o.scenario_path = kSwarm;
  o.duration = 10min;
  o.out_dir = dir;
  o.record.format = RecordFormat::kHdf5;
  int polls = 0;
  o.stop_requested = [&polls] { return ++polls > 4; };
  auto r = run_scenario(o);
  ASSERT_TRUE(r.ok()) << r.error();
  ASSERT_TRUE(r->interrupted);
  ASSERT_GT(r->steps, 50u);
  ASSERT_LT(r->steps, 20000u);
  H5File f(dir / "steps.h5");
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f.attribute<std::uint8_t>("interrupted", H5T_NATIVE_UINT8), 1u);
  EXPECT_EQ(f.attribute<std::uint64_t>("steps", H5T_NATIVE_UINT64), r->steps);
  EXPECT_DOUBLE_EQ(f.attribute<double>("simulated_s", H5T_NATIVE_DOUBLE), r->simulated_seconds);
  const auto step = f.read<std::uint64_t>("step", H5T_NATIVE_UINT64);
  ASSERT_EQ(step.size(), r->steps);
  for (std::size_t t = 0; t < step.size(); ++t) ASSERT_EQ(step[t], t + 1);
  const auto pose = f.read<double>("pose", H5T_NATIVE_DOUBLE);
  const std::size_t robots = r->robots.size();
  for (std::size_t i = 0; i < robots; ++i) {
    const std::size_t k = (step.size() - 1) * robots + i;
    EXPECT_EQ(pose[3 * k], r->robots[i].end.x);
    EXPECT_EQ(pose[3 * k + 1], r->robots[i].end.y);
  }
  EXPECT_NE(read_text(dir / "summary.txt").find("recording: hdf5, " + std::to_string(r->steps) + " steps x 12 robots"),
            std::string::npos)
      << read_text(dir / "summary.txt");
  fs::remove_all(dir);
}

// Ctrl-C on the `symb` binary itself: SIGINT mid-run, exit 130, a steps.h5 that opens and holds
// the steps summary.txt counts.
TEST(Recording, CtrlCOnTheBinaryLeavesAClosedHdf5File) {
  const fs::path dir = scratch_dir("sigint");
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1);
    ::dup2(null, 2);
    ::execl(SYMB_BINARY, SYMB_BINARY, "run", kSwarm.c_str(), "--out", dir.c_str(), "--duration", "10min", "--speed",
            "50", "--record", "hdf5", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  // Wait until the file has its first blocks (256 steps of 12 robots: 7.7 s simulated).
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  std::error_code ec;
  while ((!fs::exists(dir / "steps.h5", ec) || fs::file_size(dir / "steps.h5", ec) < 40000) &&
         std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(20ms);
  ::kill(pid, SIGINT);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  const std::string summary = read_text(dir / "summary.txt");
  const std::smatch m = [&] {
    std::smatch x;
    std::regex_search(summary, x, std::regex("simulated: [0-9.]+ s in ([0-9]+) steps"));
    return x;
  }();
  ASSERT_EQ(m.size(), 2u) << summary;
  const std::uint64_t steps = std::stoull(m[1].str());
  H5File f(dir / "steps.h5");
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f.attribute<std::uint8_t>("interrupted", H5T_NATIVE_UINT8), 1u);
  EXPECT_EQ(f.dims("pose"), (std::vector<hsize_t>{steps, 12, 3}));
  EXPECT_GE(steps, 256u) << "the first block was on disk before the signal";
  fs::remove_all(dir);
}

std::pair<int, std::string> symb_run(const std::string& args) {
  const fs::path err = scratch_dir("err.txt");
  const int status =
      std::system(("'" + std::string(SYMB_BINARY) + "' run " + args + " >/dev/null 2>'" + err.string() + "'").c_str());
  std::string text = read_text(err);
  fs::remove(err);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text};
}

TEST(Recording, BadOptionValuesGetErrorsThatNameThem) {
  const std::string base = "'" + kSwarm + "' --duration 1s --out '" + scratch_dir("bad").string() + "' ";
  auto [code, err] = symb_run(base + "--record xml");
  EXPECT_EQ(code, 2);
  EXPECT_NE(err.find("--record: expected csv, hdf5, both, none or auto, not 'xml'"), std::string::npos) << err;
  std::tie(code, err) = symb_run(base + "--record-every 0");
  EXPECT_EQ(code, 2);
  EXPECT_NE(err.find("--record-every: '0' is out of range"), std::string::npos) << err;
  std::tie(code, err) = symb_run(base + "--csv-every 2 --record-every 3");
  EXPECT_EQ(code, 2);
  EXPECT_NE(err.find("--record-every 3: the step interval was given already as 2"), std::string::npos) << err;
  std::tie(code, err) = symb_run(base + "--record-robots thymio1,,thymio2");
  EXPECT_EQ(code, 1);
  EXPECT_NE(err.find("--record-robots: column 9: empty item"), std::string::npos) << err;
  std::tie(code, err) = symb_run(base + "--record-robots thymio1..thymio40");
  EXPECT_EQ(code, 1);
  EXPECT_NE(err.find("--record-robots: column 10: no robot named 'thymio40'"), std::string::npos) << err;
  fs::remove_all(scratch_dir("bad"));

  const std::vector<std::string> names = {"a", "b", "c", "d"};
  auto picked = resolve_record_robots("d,a..b", names);
  ASSERT_TRUE(picked.ok()) << picked.error();
  EXPECT_EQ(*picked, (std::vector<std::size_t>{0, 1, 3}));
  auto reversed = resolve_record_robots("a,c..b", names);
  ASSERT_FALSE(reversed.ok());
  EXPECT_EQ(reversed.error(), "--record-robots: column 3: 'b' comes before 'c' in the scenario");
  EXPECT_FALSE(resolve_record_robots("", names).ok());
  EXPECT_FALSE(resolve_record_robots("a,", names).ok());
}

TEST(Recording, TheTrailSampleIsSeededAndCoversEveryRobotOfASmallRun) {
  const auto a = sample_robots(1000, 24, 7);
  EXPECT_EQ(a, sample_robots(1000, 24, 7));
  EXPECT_NE(a, sample_robots(1000, 24, 8));
  ASSERT_EQ(a.size(), 24u);
  EXPECT_TRUE(std::is_sorted(a.begin(), a.end()));
  EXPECT_EQ(std::set<std::size_t>(a.begin(), a.end()).size(), 24u);
  EXPECT_LT(a.back(), 1000u);
  // Spread over the swarm, not its first robots: the sample's mean index is near the middle.
  double mean = 0;
  for (std::size_t i : a) mean += static_cast<double>(i) / 24;
  EXPECT_GT(mean, 300);
  EXPECT_LT(mean, 700);
  EXPECT_EQ(sample_robots(5, 24, 7), (std::vector<std::size_t>{0, 1, 2, 3, 4}));
}

// The density map's cells: drawn where robots were, at the level their count gives.
TEST(Recording, DensityMapColoursEachCellByItsTime) {
  sim::WorldSpec world;
  world.width = 400;
  world.height = 200;
  DensityGrid grid(world.width, world.height, 40);  // 10 cm cells, 40 x 20
  ASSERT_EQ(grid.columns(), 40u);
  ASSERT_EQ(grid.rows(), 20u);
  for (int k = 0; k < 64; ++k) grid.add(15, 15);  // cell (1, 1)
  for (int k = 0; k < 16; ++k) grid.add(395, 5);  // cell (39, 0)
  grid.add(-3, 250);                              // outside: the nearest cell (0, 19)
  EXPECT_EQ(grid.at(1, 1), 64u);
  EXPECT_EQ(grid.at(39, 0), 16u);
  EXPECT_EQ(grid.at(0, 19), 1u);
  std::ostringstream svg;
  write_density_svg(svg, world, grid, 0.5, "density test");
  const std::string text = svg.str();
  EXPECT_EQ(occurrences(text, "class=\"cell\""), 3u);
  EXPECT_EQ(occurrences(text, "data-level=\"63\""), 1u);  // the busiest, top of the scale
  EXPECT_EQ(occurrences(text, "data-level=\"15\""), 1u);  // a quarter of it: ceil(64 / 4) - 1
  EXPECT_EQ(occurrences(text, "data-level=\"0\""), 1u);   // one visit: the bottom
  // The legend reads robot-seconds up to the busiest cell's 64 x 0.5 s.
  EXPECT_NE(text.find("<g id=\"legend\""), std::string::npos);
  EXPECT_NE(text.find("max 32.00"), std::string::npos);
  EXPECT_NE(text.find(">30</text>"), std::string::npos) << "a tick at 30 robot-seconds";
  // Cell (1, 1) at 900 px / 400 cm = 2.25 px per cm: x = 20 + 10 * 2.25, y = 20 + (200 - 20) * 2.25.
  EXPECT_NE(text.find("data-level=\"63\" x=\"42.5\" y=\"425.0\" width=\"22.5\" height=\"22.5\""), std::string::npos)
      << text.substr(0, 2000);
}

std::string crowd_scenario(const fs::path& dir, int robots) {
  const fs::path file = dir / "crowd.yaml";
  std::ofstream out(file, std::ios::binary);
  out << "name: crowd\nseed: 11\nduration: 2s\ncontrol_period: 30ms\nworld:\n  arena: {width: 600, height: 400}\n"
         "  walls:\n    - [300, 0, 300, 150]\nrobots:\n  - name: c\n    count: "
      << robots
      << "\n    start: random\n    tasks:\n      - name: controller\n        type: mdl2e\n        params: {program: "
      << SYMB_SCENARIO_DIR << "/mdl2e/obstacle_avoidance.mdl2e}\n    hooks:\n      - ir -> controller -> wheels\n";
  return file.string();
}

std::vector<std::size_t> bar_counts(const std::string& svg, std::size_t histogram) {
  std::vector<std::size_t> counts;
  std::size_t at = 0;
  for (std::size_t h = 0; h <= histogram; ++h) at = svg.find("<g class=\"histogram\">", at + 1);
  const std::size_t end = svg.find("</g>", at);
  const std::regex bar("data-count=\"([0-9]+)\"");
  const std::string part = svg.substr(at, end - at);
  for (auto it = std::sregex_iterator(part.begin(), part.end(), bar); it != std::sregex_iterator(); ++it)
    counts.push_back(std::stoul((*it)[1].str()));
  return counts;
}

TEST(Recording, ACrowdGetsADensityMapSampledTrailsAndRobotStatistics) {
  const fs::path dir = scratch_dir("crowd");
  fs::create_directories(dir);
  RunOptions o;
  o.scenario_path = crowd_scenario(dir, 150);
  o.out_dir = dir / "out";
  auto r = run_scenario(o);
  ASSERT_TRUE(r.ok()) << r.error();
  const fs::path out = dir / "out";
  // auto: more than 100 robots record HDF5, and draw the crowd's pictures instead of a path each.
  EXPECT_TRUE(fs::exists(out / "steps.h5"));
  EXPECT_FALSE(fs::exists(out / "steps.csv"));
  EXPECT_FALSE(fs::exists(out / "trajectory.svg"));
  EXPECT_EQ(r->recording.format, "hdf5");
  EXPECT_TRUE(r->recording.crowd);

  const std::string density = read_text(out / "density.svg");
  EXPECT_GT(occurrences(density, "class=\"cell\""), 50u) << "150 robots over 2 s cover many cells";
  EXPECT_GE(occurrences(density, "data-level=\"63\""), 1u);
  EXPECT_NE(density.find("<g id=\"legend\""), std::string::npos);
  EXPECT_NE(density.find("robot-seconds"), std::string::npos);

  const std::string trails = read_text(out / "trails.svg");
  EXPECT_EQ(occurrences(trails, "<polyline"), kTrailSample);
  EXPECT_EQ(occurrences(trails, "<circle cx=") - 2 * kTrailSample, 150u) << "a grey dot per robot's end";
  EXPECT_NE(trails.find("trails of 24 of 150 robots (sampled by seed 11)"), std::string::npos);

  std::istringstream stats(read_text(out / "robot_stats.csv"));
  std::string line;
  std::getline(stats, line);
  EXPECT_EQ(line, "robot,distance_m,contacts,contact_steps,moving_s,mean_speed_cm_s,end_x_cm,end_y_cm");
  std::size_t rows = 0;
  while (std::getline(stats, line)) {
    ASSERT_EQ(line.rfind("c" + std::to_string(rows) + ",", 0), 0u) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 150u);

  const std::string histograms = read_text(out / "robot_stats.svg");
  ASSERT_EQ(occurrences(histograms, "<g class=\"histogram\">"), 3u);
  for (std::size_t h = 0; h < 3; ++h) {
    const auto counts = bar_counts(histograms, h);
    std::size_t total = 0;
    for (std::size_t c : counts) total += c;
    EXPECT_EQ(total, 150u) << "histogram " << h << ": every robot in one bar";
    EXPECT_GE(counts.size(), 1u);
  }
  EXPECT_NE(histograms.find("mean speed (cm/s)"), std::string::npos);
  fs::remove_all(dir);
}

// A small run keeps its one picture with a path per robot, and --record none writes no steps.
TEST(Recording, ASmallRunKeepsItsTrajectoryPicture) {
  const fs::path dir = scratch_dir("small");
  RunOptions o;
  o.scenario_path = kSwarm;
  o.duration = 1s;
  o.out_dir = dir;
  o.record.format = RecordFormat::kNone;
  auto r = run_scenario(o);
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(occurrences(read_text(dir / "trajectory.svg"), "<polyline"), 12u);
  EXPECT_FALSE(fs::exists(dir / "steps.csv"));
  EXPECT_FALSE(fs::exists(dir / "steps.h5"));
  EXPECT_FALSE(fs::exists(dir / "density.svg"));
  fs::remove_all(dir);
}

// h5py, as a person reads the file: the layout docs/run.md gives works as written.
TEST(Recording, H5pyReadsTheFileAsDocumented) {
  if (std::system("/usr/bin/python3 -c 'import h5py' 2>/dev/null") != 0)
    GTEST_SKIP() << "python3-h5py is not installed (scripts/setup installs it)";
  const fs::path dir = scratch_dir("h5py");
  RecordOptions o;
  o.format = RecordFormat::kHdf5;
  const RecordedRun run = record_run(kSwarm, 1s, o, 2, dir);
  ASSERT_EQ(run.steps.size(), 33u);
  const fs::path script = dir / "read.py";
  {
    std::ofstream s(script);
    s << "import h5py\n"
         "f = h5py.File('"
      << (dir / "steps.h5").string()
      << "', 'r')\n"
         "x = f['pose'][:, :, 0]\n"
         "names = list(f['robots'].asstr()[:])\n"
         "print(f.attrs['scenario'], f.attrs['seed'], x.shape, names[3], repr(float(x[-1, 3])), "
         "f['pose'].attrs['columns'])\n";
  }
  FILE* pipe = ::popen(("/usr/bin/python3 '" + script.string() + "'").c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::array<char, 512> buf{};
  std::string output;
  for (std::size_t n; (n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0;) output.append(buf.data(), n);
  EXPECT_EQ(::pclose(pipe), 0);
  // Python's repr is the shortest text that reads back: compare it as a number.
  const auto cut = output.find(' ', output.find("thymio3 ") + 8);
  ASSERT_NE(cut, std::string::npos) << output;
  EXPECT_EQ(output.substr(0, output.find("thymio3 ") + 8), "swarm 7 (17, 12) thymio3 ") << output;
  EXPECT_EQ(std::stod(output.substr(output.find("thymio3 ") + 8)), run.steps[32].robots[3].state.pose.x) << output;
  EXPECT_EQ(output.substr(cut), " x_cm,y_cm,heading_rad\n") << output;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace symb::apps::run
