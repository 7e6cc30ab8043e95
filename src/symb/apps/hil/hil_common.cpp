#include "symb/apps/hil/hil_common.hpp"

#include <algorithm>
#include <csignal>
#include <cstdio>

namespace symb::apps::hil {

namespace {

volatile std::sig_atomic_t interrupted = 0;

extern "C" void on_interrupt(int) { interrupted = 1; }

}  // namespace

std::variant<SplitArgs, UsageError> split_args(std::span<const std::string_view> args,
                                               std::span<const OptionSpec> specs, std::size_t max_positional) {
  SplitArgs out;
  std::vector<std::string_view> rest;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string_view a = args[i];
    if (a.starts_with("-") && a.size() > 1) {
      rest.push_back(a);
      const bool has_value = a.find('=') == std::string_view::npos &&
                             std::any_of(specs.begin(), specs.end(),
                                         [&](const OptionSpec& s) { return s.name == a && !s.value_name.empty(); });
      if (has_value && i + 1 < args.size()) rest.push_back(args[++i]);
    } else {
      out.positional.push_back(a);
    }
  }
  auto parsed = parse_options(rest, specs);
  if (auto* e = std::get_if<UsageError>(&parsed)) return *e;
  out.options = std::get<std::vector<ParsedOption>>(parsed);
  for (const ParsedOption& o : out.options)
    if (o.name == "--help") out.help = true;
  if (!out.help && out.positional.size() > max_positional)
    return UsageError{"unexpected argument " + quote_arg(out.positional[max_positional])};
  return out;
}

InterruptFlag::InterruptFlag() {
  interrupted = 0;
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
}

InterruptFlag::~InterruptFlag() {
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
}

bool InterruptFlag::raised() const { return interrupted != 0; }

std::uint64_t robot_seed(std::uint64_t seed, std::size_t index) {
  std::uint64_t z = seed + 0x9e3779b97f4a7c15ULL * (index + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

void PrefixedLogSink::write(const os::LogEntry& e) {
  std::lock_guard lock(mu_);
  out_ << prefix_ << os::format_log_entry(e) << '\n' << std::flush;
}

std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

}  // namespace symb::apps::hil
