// `symb link`: the serial cables between a simulator and a board, made of pseudo-terminals.
// Each line is two pty pairs whose masters this process relays, so each side opens a stable
// path (a symlink in DIR) of its own, as with `socat pty,link=A pty,link=B`, and either side may
// start, stop and restart without the other's path changing.
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <thread>
#include <vector>

#include "symb/apps/hil/hil_commands.hpp"
#include "symb/apps/hil/hil_common.hpp"
#include "symb/io/pty_pair.hpp"
#include "symb/sim/hil_protocol.hpp"

namespace symb::apps::hil {

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr std::string_view kLinkCommand = "symb link";

constexpr OptionSpec kLinkOptions[] = {
    {"--dir", "DIR", "where the four paths are made (default /tmp/symb-link-<pid>)"},
    {"--corrupt", "P", "corrupt this fraction of the data line's frames, both ways (0..1, default 0)"},
    {"--seed", "S", "seed of the fault injector (default 1)"},
    {"--duration", "D", "stop after this long (default: at Ctrl-C)"},
    {"--help", "", "this help"},
};

void print_link_help(std::ostream& out) {
  out << "Usage: " << kLinkCommand << " [options]\n\n"
      << "Makes the two serial lines of one hardware-in-the-loop board out of pseudo-terminals and\n"
      << "relays them until Ctrl-C: the data line (simulator <-> board: IR frames one way, wheel\n"
      << "frames the other) and the shell line (board <-> a person's `symb shell`). It prints the\n"
      << "paths and the commands to run with them.\n\n"
      << "Options:\n"
      << describe_options(kLinkOptions) << "\n"
      << "With --corrupt, one byte of the chosen frames is changed (never a framing byte), so every\n"
      << "corrupted frame is one bad frame at the receiver; the counts are printed.\n";
}

// One direction of one line.
struct Relay {
  std::shared_ptr<io::SerialPort> from;
  std::shared_ptr<io::SerialPort> to;
  std::unique_ptr<sim::FrameCorruptor> corruptor;  // data line only
  std::atomic<std::uint64_t> bytes{0};
  std::atomic<std::uint64_t> lost{0};  // bytes the other side's line did not take
  std::atomic<std::uint64_t> frames{0};
  std::atomic<std::uint64_t> corrupted{0};
  std::thread thread;

  void run(const std::atomic<bool>& stop) {
    std::vector<std::byte> buf(4096), out;
    while (!stop.load()) {
      auto got = from->read_some(buf, 50ms);
      if (!got) {
        std::this_thread::sleep_for(50ms);
        continue;
      }
      if (*got == 0) continue;
      std::span<const std::byte> chunk(buf.data(), *got);
      if (corruptor) {
        out.clear();
        corruptor->feed(chunk, out);
        frames.store(corruptor->frames());
        corrupted.store(corruptor->corrupted());
        chunk = out;
      }
      bytes.fetch_add(chunk.size());
      // Nobody on the other side reads: the bytes are dropped, as on a cable with no one there.
      if (!chunk.empty() && !to->write_all(chunk)) lost.fetch_add(chunk.size());
    }
  }
};

}  // namespace

int run_link_command(std::span<const std::string_view> args, const CliContext& ctx) {
  auto split = split_args(args, kLinkOptions, 0);
  if (auto* e = std::get_if<UsageError>(&split)) return usage_error(ctx, kLinkCommand, *e);
  const SplitArgs& a = std::get<SplitArgs>(split);
  if (a.help) {
    print_link_help(ctx.out);
    return kExitOk;
  }
  fs::path dir = fs::temp_directory_path() / ("symb-link-" + std::to_string(::getpid()));
  double corrupt = 0;
  std::uint64_t seed = 1;
  std::optional<kernel::Duration> duration;
  for (const ParsedOption& o : a.options) {
    if (o.name == "--dir") {
      if (o.value.empty()) return usage_error(ctx, kLinkCommand, UsageError{"--dir: empty folder name"});
      dir = o.value;
    } else if (o.name == "--corrupt") {
      auto v = parse_fraction("--corrupt", o.value);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kLinkCommand, *e);
      corrupt = std::get<double>(v);
    } else if (o.name == "--seed") {
      auto v = parse_u64("--seed", o.value);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kLinkCommand, *e);
      seed = std::get<std::uint64_t>(v);
    } else if (o.name == "--duration") {
      auto v = parse_duration("--duration", o.value, std::chrono::hours(24 * 365));
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kLinkCommand, *e);
      duration = std::get<kernel::Duration>(v);
    }
  }

  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) {
    ctx.err << kLinkCommand << ": cannot create " << dir.string() << ": " << ec.message() << "\n";
    return kExitFailure;
  }
  const char* names[4] = {"sim", "board", "board-shell", "shell"};
  std::vector<io::PtyPair> pairs;
  std::vector<fs::path> links;
  for (const char* name : names) {
    auto p = io::PtyPair::open(std::string("link.") + name);
    if (!p) {
      ctx.err << kLinkCommand << ": " << p.error() << "\n";
      return kExitFailure;
    }
    // The relay must never stall on a side that does not read.
    p->master->set_write_timeout(20ms);
    const fs::path link = dir / name;
    if (fs::is_symlink(link, ec) || fs::exists(link, ec)) fs::remove(link, ec);
    fs::create_symlink(p->slave_path, link, ec);
    if (ec) {
      ctx.err << kLinkCommand << ": cannot make " << link.string() << ": " << ec.message() << "\n";
      return kExitFailure;
    }
    links.push_back(link);
    pairs.push_back(std::move(p).value());
  }

  Relay relays[4];
  relays[0].from = pairs[0].master;  // simulator -> board
  relays[0].to = pairs[1].master;
  relays[1].from = pairs[1].master;  // board -> simulator
  relays[1].to = pairs[0].master;
  relays[2].from = pairs[2].master;  // board shell -> person
  relays[2].to = pairs[3].master;
  relays[3].from = pairs[3].master;  // person -> board shell
  relays[3].to = pairs[2].master;
  if (corrupt > 0) {
    relays[0].corruptor = std::make_unique<sim::FrameCorruptor>(corrupt, seed, 1);
    relays[1].corruptor = std::make_unique<sim::FrameCorruptor>(corrupt, seed, 2);
  }
  std::atomic<bool> stop{false};
  InterruptFlag interrupt;
  for (Relay& r : relays) r.thread = std::thread([&r, &stop] { r.run(stop); });

  const std::string d = dir.string();
  ctx.out << "symb link: the serial lines of one board, relayed until Ctrl-C\n"
          << "  data line:  " << d << "/sim <-> " << d << "/board\n"
          << "  shell line: " << d << "/board-shell <-> " << d << "/shell\n"
          << (corrupt > 0 ? "  fault injection: " + fixed(100 * corrupt, 2) + "% of data frames corrupted, both ways\n"
                          : "")
          << "Run the board, then the simulator, each in a terminal of its own:\n"
          << "  symb board SCENARIO --serial " << d << "/board --shell " << d << "/board-shell\n"
          << "  symb sim SCENARIO --serial " << d << "/sim\n"
          << "and, for the board's command shell:\n"
          << "  symb shell --serial " << d << "/shell\n"
          << std::flush;

  const auto start = std::chrono::steady_clock::now();
  auto last_print = start;
  std::uint64_t printed = 0;
  const auto report = [&] {
    ctx.err << "link: sim->board " << relays[0].bytes.load() << " bytes";
    if (corrupt > 0)
      ctx.err << ", " << relays[0].frames.load() << " frames, " << relays[0].corrupted.load() << " corrupted";
    ctx.err << "; board->sim " << relays[1].bytes.load() << " bytes";
    if (corrupt > 0)
      ctx.err << ", " << relays[1].frames.load() << " frames, " << relays[1].corrupted.load() << " corrupted";
    ctx.err << "; dropped (no reader) " << relays[0].lost.load() + relays[1].lost.load() << " bytes\n" << std::flush;
  };
  while (!interrupt.raised() && (!duration || std::chrono::steady_clock::now() - start < *duration)) {
    std::this_thread::sleep_for(50ms);
    const auto now = std::chrono::steady_clock::now();
    const std::uint64_t moved = relays[0].bytes.load() + relays[1].bytes.load();
    if (now - last_print >= 5s && moved != printed) {
      report();
      printed = moved;
      last_print = now;
    }
  }
  stop = true;
  for (Relay& r : relays) r.thread.join();
  report();
  for (const fs::path& l : links) fs::remove(l, ec);
  fs::remove(dir, ec);  // only if empty: a folder the person gave may hold other things
  return kExitOk;
}

}  // namespace symb::apps::hil
