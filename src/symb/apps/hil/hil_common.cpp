#include "symb/apps/hil/hil_common.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <thread>

#include "symb/os/param.hpp"
#include "symb/shell/shell_task.hpp"

namespace symb::apps::hil {

std::variant<bool, UsageError> parse_dds_option(const ParsedOption& o, io::DdsFrameOptions& options,
                                                std::string& given) {
  if (o.name == "--domain") {
    auto v = parse_count("--domain", o.value, 0, 232);
    if (auto* e = std::get_if<UsageError>(&v)) return *e;
    options.domain = static_cast<std::uint32_t>(std::get<std::uint64_t>(v));
  } else if (o.name == "--prefix") {
    if (!os::is_valid_name(o.value)) return UsageError{"--prefix " + quote_arg(o.value) + ": not a name"};
    options.prefix = o.value;
  } else if (o.name == "--lease") {
    auto v = parse_duration(o.name, o.value, std::chrono::hours(1));  // refuses 0
    if (auto* e = std::get_if<UsageError>(&v)) return *e;
    options.lease = std::get<kernel::Duration>(v);
  } else {
    return false;
  }
  given = o.name;
  return true;
}

void PrefixedLogSink::write(const os::LogEntry& e) {
  std::lock_guard lock(mu_);
  out_ << prefix_ << os::format_log_entry(e) << '\n' << std::flush;
}

kernel::Result<BoardView> BoardView::start(const view::ViewRequest& request, const std::string& robot, os::Node& node,
                                           const std::string& scenario, std::ostream& notice) {
  BoardView b;
  if (!request.on) return kernel::Result<BoardView>(std::move(b));
  auto started = view::LiveView::start(view::nodes_view_target({robot}, {&node}), scenario, 0, nullptr,
                                       view::live_view_options(request));
  if (!started) return kernel::Error{started.error()};
  b.live_ = std::move(started).value();
  b.node_ = &node;
  view::LiveView* v = b.live_.get();
  node.set_probe_sink([v](const os::ProbeSample& s) { v->on_probe(s); });
  notice << "view: " << b.live_->url() << "\n" << std::flush;
  return kernel::Result<BoardView>(std::move(b));
}

void BoardView::stop() {
  if (!live_) return;
  live_->finish();
  node_->set_probe_sink({});
  live_.reset();
}

kernel::Result<FrameBoardEnd> run_frame_board(const FrameBoardRun& run, const CliContext& ctx) {
  using namespace std::chrono_literals;
  os::Node& node = *run.node;
  const std::string who = "board " + run.robot + ": ";
  auto log_sink = std::make_shared<PrefixedLogSink>(ctx.err, who);
  if (!run.quiet) {
    for (const os::LogEntry& e : node.log().since(0)) log_sink->write(e);
    node.log().add_sink(log_sink);
  }
  const auto fail = [&](const std::string& why) -> kernel::Result<FrameBoardEnd> {
    node.log().remove_sink(log_sink);
    return kernel::Error{why};
  };
  if (run.shell_port) {
    auto table = std::make_shared<shell::DeviceTable>();
    for (const auto& d : run.devices) (*table)[d->name()] = d;
    (*table)["uart0"] = run.data;
    (*table)["uart1"] = run.shell_port;
    shell::ShellOptions so;
    so.devices = table;
    if (auto attached = shell::attach_shell(node, run.shell_port, so); !attached)
      return fail("shell: " + attached.error());
  }
  if (auto st = run.board->start(); !st) return fail(st.error());
  // The web view reads the node between two frames, where none of its tasks runs.
  auto view_started = BoardView::start(run.view, run.robot, node, run.scenario, ctx.err);
  if (!view_started) return fail(view_started.error());
  BoardView view = std::move(view_started).value();
  ctx.out << "board: " << run.what << " " << run.robot << " of " << run.scenario << " on " << run.where
          << (run.shell_port ? ", shell on " + run.shell_path : std::string()) << "; " << node.task_count()
          << " tasks; its clock follows the simulator's frames; Ctrl-C to stop\n"
          << std::flush;

  FrameBoardEnd end;
  const kernel::WallClock wall;  // the line's outages are timed on it (FrameBoardEnd::at)
  InterruptFlag interrupt;
  const auto start = std::chrono::steady_clock::now();
  auto next_stats = start + run.stats_every;
  while (!interrupt.raised() && (!run.duration || std::chrono::steady_clock::now() - start < *run.duration)) {
    if (end.line.down()) {
      if (end.line.due(wall.now())) {
        if (auto st = run.data->open(); st) {
          (void)run.data->ioctl("flush");
          ctx.err << who << "serial line open again after " << kernel::to_milliseconds(end.line.reopened(wall.now()))
                  << " ms\n"
                  << std::flush;
        } else {
          const auto wait = end.line.failed(wall.now());
          ctx.err << who << "reopen attempt " << end.line.attempts() << " failed: " << st.error() << "; next in "
                  << kernel::to_milliseconds(wait) << " ms\n"
                  << std::flush;
        }
      }
      if (end.line.down()) std::this_thread::sleep_for(20ms);
    } else if (auto served = run.board->serve(20ms); !served) {
      if (!run.reopen) {
        if (!run.gone(served.error())) break;
        std::this_thread::sleep_for(20ms);
        continue;
      }
      end.line.lost(wall.now());
      ctx.err << who << served.error() << ": reopening it with backoff\n" << std::flush;
    }
    run.executor->run_injected();  // the shell's input, between frames
    view.between();
    if (end.cycle = node.cycle_error(); !end.cycle.empty()) break;
    if (std::chrono::steady_clock::now() >= next_stats) {
      next_stats += run.stats_every;
      ctx.err << "board: " << run.stats() << "\n" << std::flush;
    }
  }
  end.at = wall.now();
  node.log().remove_sink(log_sink);
  view.stop();
  return end;
}

std::string frame_board_stats_line(const sim::FrameClockStats& s, const FrameBoardEnd& end, const std::string& extra) {
  const auto n = [](std::uint64_t v) { return std::to_string(v); };
  return "board-stats: good=" + n(s.frames) + " bad=" + n(s.bad_frames()) + " missed=" + n(s.missed) +
         " out_of_order=" + n(s.out_of_order) + " malformed=" + n(s.malformed) + " jumps=" + n(s.jumps) +
         " handshakes=" + n(s.handshakes) + " restarts=" + n(s.restarts) + " answers=" + n(s.answers) + extra +
         " not_taken=" + n(s.write_errors) + " losses=" + n(s.link_losses) + " recoveries=" + n(s.link_recoveries) +
         " bytes_in=" + n(s.bytes_in) + " line_losses=" + n(end.line.losses()) +
         " line_reopens=" + n(end.line.reopens()) +
         " line_down_ms=" + std::to_string(kernel::to_milliseconds(end.line.down_for(end.at))) +
         " line_open=" + (end.line.down() ? "0" : "1");
}

std::string frame_board_failure(const FrameBoardEnd& end, const std::string& serial) {
  if (!end.cycle.empty()) return end.cycle;
  if (!end.line.down()) return {};
  return "the serial line " + serial + " was down when the board stopped (down " +
         fixed(std::chrono::duration<double>(end.line.down_for(end.at)).count(), 1) + " s in all, " +
         std::to_string(end.line.losses()) + " loss(es), " + std::to_string(end.line.reopens()) + " reopening(s))";
}

}  // namespace symb::apps::hil
