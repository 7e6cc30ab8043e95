#include "symb/apps/hil/hil_common.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <thread>

#include "symb/os/param.hpp"

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

FrameBoardEnd run_frame_board_loop(const FrameBoardLoop& loop, std::ostream& err) {
  using namespace std::chrono_literals;
  FrameBoardEnd end;
  const kernel::WallClock wall;  // the line's outages are timed on it (FrameBoardEnd::at)
  const auto steady = [&wall] { return wall.now(); };
  const std::string who = "board " + loop.robot + ": ";
  InterruptFlag interrupt;
  const auto start = std::chrono::steady_clock::now();
  auto next_stats = start + loop.stats_every;
  while (!interrupt.raised() && (!loop.duration || std::chrono::steady_clock::now() - start < *loop.duration)) {
    if (end.line.down()) {
      if (end.line.due(steady())) {
        if (auto st = loop.port->open(); st) {
          (void)loop.port->ioctl("flush");
          err << who << "serial line open again after " << kernel::to_milliseconds(end.line.reopened(steady()))
              << " ms\n"
              << std::flush;
        } else {
          const auto wait = end.line.failed(steady());
          err << who << "reopen attempt " << end.line.attempts() << " failed: " << st.error() << "; next in "
              << kernel::to_milliseconds(wait) << " ms\n"
              << std::flush;
        }
      }
      if (end.line.down()) std::this_thread::sleep_for(20ms);
    } else if (auto served = loop.serve(20ms); !served) {
      if (!loop.port) {
        if (!loop.gone(served.error())) break;
        std::this_thread::sleep_for(20ms);
        continue;
      }
      end.line.lost(steady());
      err << who << served.error() << ": reopening it with backoff\n" << std::flush;
    }
    if (loop.between) loop.between();
    if (end.cycle = loop.node->cycle_error(); !end.cycle.empty()) break;
    if (std::chrono::steady_clock::now() >= next_stats) {
      next_stats += loop.stats_every;
      err << "board: " << loop.stats() << "\n" << std::flush;
    }
  }
  end.at = steady();
  return end;
}

}  // namespace symb::apps::hil
