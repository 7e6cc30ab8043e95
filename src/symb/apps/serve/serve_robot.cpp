// `symb serve --scenario S --robot NAME`: one robot of a split world (serve_command.hpp).
#include <chrono>
#include <string>
#include <thread>

#include "symb/apps/run/remote_robots.hpp"
#include "symb/apps/serve/serve_command.hpp"
#include "symb/io/dds/dds_frame_stream.hpp"
#include "symb/io/plugin_library.hpp"
#include "symb/os/syslog.hpp"
#include "symb/sim/hil_split_robot.hpp"
#include "symb/sim/scenario.hpp"

namespace symb::apps::serve {

namespace {

constexpr std::string_view kServeRobot = "symb serve";

}  // namespace

int run_serve_robot(const ServeRobotArgs& args, const CliContext& ctx) {
  auto fail = [&](const std::string& text) {
    ctx.err << kServeRobot << ": " << text << "\n";
    return kExitFailure;
  };
  auto scenario = sim::load_scenario(args.scenario);
  if (!scenario) return fail(scenario.error());
  sim::HilSplitRobotOptions options;
  for (const std::string& path : args.plugins) {
    auto lib = io::PluginLibrary::open(path);
    if (!lib) return fail("--plugin: " + lib.error());
    options.task_types.push_back(
        [lib = std::move(lib).value()](os::TaskTypeRegistry& r) { return lib->register_into(r); });
  }
  const std::string who = "serve " + args.robot;
  options.on_event = [&](const std::string& text) { ctx.out << who << ": " << text << "\n" << std::flush; };
  auto links = io::DdsFrameLinks::create(args.dds);
  if (!links) return fail(links.error());
  auto stream = (*links)->stream(args.robot, run::kToWorld, run::kToRobot);
  if (!stream) return fail(stream.error());
  auto made = sim::HilSplitRobot::create(*scenario, args.robot, *stream, std::move(options));
  if (!made) return fail(made.error());
  sim::HilSplitRobot& robot = **made;
  io::DdsFrameStream& s = **stream;
  ctx.out << who << ": waiting for the world on " << s.read_topic() << " (domain " << args.dds.domain << ")\n"
          << std::flush;

  const auto started = std::chrono::steady_clock::now();
  std::string ended;
  bool ok = true;
  for (;;) {
    auto served = robot.serve(std::chrono::milliseconds(100));
    if (robot.ended()) {
      ended = "the world ended the run after " + std::to_string(*robot.ended()) + " steps";
      break;
    }
    if (robot.system() == nullptr && std::chrono::steady_clock::now() - started > args.wait) {
      ok = false;
      ended = "no world came within " + std::to_string(kernel::to_milliseconds(args.wait)) + " ms";
      break;
    }
    if (served) continue;
    if (robot.system() == nullptr && !s.is_open()) {
      // Not the world yet (a foreign writer that came and went): wait on for the world's hello.
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    const io::DdsPeerState peer = s.peer();
    ok = false;
    ended = peer == io::DdsPeerState::kLeft || peer == io::DdsPeerState::kLost
                ? "the world is gone without ending the run (" + served.error() + ")"
                : served.error();
    break;
  }
  const sim::HilSplitRobotBoardStats st = robot.stats();
  ctx.out << who << ": " << ended << " at " << std::chrono::duration<double>(robot.now()).count() << " s of node time\n"
          << "serve-stats: frames=" << st.frames << " missed=" << st.missed << " out_of_order=" << st.out_of_order
          << " hellos=" << st.hellos << " bad=" << st.bad_frames() << " crc=" << st.decoder.crc_errors
          << " malformed=" << st.malformed << " answers=" << st.answers << " not_taken=" << st.write_errors
          << " radio_in=" << st.radio_in << " radio_dropped=" << st.radio_dropped << " radio_stale=" << st.radio_stale
          << " radio_out=" << st.radio_out << "\n";
  if (sim::RobotSystem* system = robot.system())
    for (const os::LogEntry& e : system->node().log().since(0))
      if (e.level >= os::LogLevel::kWarn) ctx.out << "log: " << os::format_log_entry(e) << "\n";
  ctx.out << std::flush;
  if (!ok) ctx.err << kServeRobot << ": " << args.robot << ": " << ended << "\n";
  return ok ? kExitOk : kExitFailure;
}

}  // namespace symb::apps::serve
