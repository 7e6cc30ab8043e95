#include "symb/apps/shell_client.hpp"

#include <poll.h>
#include <signal.h>
#include <termios.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <iostream>
#include <memory>
#include <mutex>
#include <thread>

#include "symb/io/serial_port.hpp"
#include "symb/io/tcp_stream.hpp"

namespace symb::apps {

namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

constexpr unsigned char kQuitKey = 0x1d;                  // Ctrl-]
constexpr std::string_view kAskForEcho = "\xff\xfd\x01";  // telnet IAC DO ECHO: "a person types here"

constexpr OptionSpec kSpecs[] = {
    {"--tcp", "HOST:PORT", "connect to a node's TCP shell server"},
    {"--token", "T", "the server's token, sent as the first line"},
    {"--serial", "PATH", "open a serial device or pseudo-terminal carrying a shell"},
    {"--baud", "N", "serial speed (default 115200)"},
};

// The terminal's settings while raw mode is on. A signal handler can reach nothing but statics, so
// this is the one piece of process-wide state here: the terminal itself is process-wide too.
struct SavedTerminal {
  static termios& settings() {
    static termios t{};
    return t;
  }
  static volatile sig_atomic_t& fd() {
    static volatile sig_atomic_t f = -1;
    return f;
  }
};

void restore_terminal() {
  const int fd = SavedTerminal::fd();
  if (fd >= 0) ::tcsetattr(fd, TCSANOW, &SavedTerminal::settings());
}

extern "C" void on_fatal_signal(int sig) {
  restore_terminal();  // tcsetattr is async-signal-safe
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

// Raw mode for as long as it lives.
class RawMode {
 public:
  explicit RawMode(int fd) {
    termios t{};
    if (::tcgetattr(fd, &t) != 0) return;
    SavedTerminal::settings() = t;
    SavedTerminal::fd() = fd;
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) old_[sig] = ::signal(sig, on_fatal_signal);
    termios raw = t;
    ::cfmakeraw(&raw);
    active_ = ::tcsetattr(fd, TCSANOW, &raw) == 0;
  }
  ~RawMode() {
    restore_terminal();
    SavedTerminal::fd() = -1;
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) ::signal(sig, old_[sig] == SIG_ERR ? SIG_DFL : old_[sig]);
  }
  RawMode(const RawMode&) = delete;
  RawMode& operator=(const RawMode&) = delete;
  bool active() const { return active_; }

 private:
  bool active_ = false;
  sighandler_t old_[NSIG]{};
};

bool write_fd(int fd, std::string_view data) {
  while (!data.empty()) {
    const ssize_t n = ::write(fd, data.data(), data.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno == EAGAIN) {
        pollfd p{fd, POLLOUT, 0};
        ::poll(&p, 1, 100);
        continue;
      }
      return false;
    }
    data.remove_prefix(static_cast<std::size_t>(n));
  }
  return true;
}

// Copies what the shell sends to the output, on a thread of its own, until told to stop or the
// link closes; remembers when the last bytes came.
class Printer {
 public:
  Printer(io::IOStream& link, int out_fd)
      : link_(link), out_fd_(out_fd), last_(Clock::now().time_since_epoch().count()) {
    thread_ = std::thread([this] { loop(); });
  }
  ~Printer() { stop(); }
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  bool closed() const { return closed_.load(); }
  Clock::time_point last_data() const { return Clock::time_point(Clock::duration(last_.load())); }

 private:
  void loop() {
    std::byte buf[4096];
    while (!stop_.load()) {
      auto n = link_.read_some(buf, 50ms);
      if (!n) {
        closed_ = true;
        return;
      }
      if (*n == 0) continue;
      last_ = Clock::now().time_since_epoch().count();
      if (!write_fd(out_fd_, {reinterpret_cast<const char*>(buf), *n})) {
        closed_ = true;
        return;
      }
    }
  }

  io::IOStream& link_;
  int out_fd_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> closed_{false};
  std::atomic<Clock::duration::rep> last_;
  std::thread thread_;
};

// Waits up to `timeout` for input on `fd`: its bytes, "" on timeout, nothing at its end.
std::optional<std::string> read_input(int fd, std::chrono::milliseconds timeout) {
  pollfd p{fd, POLLIN, 0};
  const int r = ::poll(&p, 1, static_cast<int>(timeout.count()));
  if (r < 0) return errno == EINTR ? std::optional<std::string>("") : std::nullopt;
  if (r == 0) return std::string();
  char buf[4096];
  const ssize_t n = ::read(fd, buf, sizeof buf);
  if (n < 0) return errno == EINTR || errno == EAGAIN ? std::optional<std::string>("") : std::nullopt;
  if (n == 0) return std::nullopt;
  return std::string(buf, static_cast<std::size_t>(n));
}

bool send(io::IOStream& link, std::string_view text) { return static_cast<bool>(link.write_all(io::as_bytes(text))); }

int interactive(io::IOStream& link, const ShellClientOptions& o, std::ostream& err, bool tcp) {
  RawMode raw(o.input_fd);
  err << "connected; Ctrl-] quits\r\n" << std::flush;
  if (tcp && !send(link, kAskForEcho)) return kExitFailure;
  if (!o.token.empty() && !send(link, o.token + "\r")) return kExitFailure;
  Printer printer(link, o.output_fd);
  while (!printer.closed()) {
    auto in = read_input(o.input_fd, 50ms);
    if (!in) break;
    if (in->empty()) continue;
    const std::size_t quit = in->find(static_cast<char>(kQuitKey));
    if (!send(link, in->substr(0, quit))) break;
    if (quit != std::string::npos) break;
  }
  printer.stop();
  const bool by_peer = printer.closed();
  restore_terminal();
  err << (by_peer ? "\r\nthe shell closed the connection\r\n" : "\r\n") << std::flush;
  return kExitOk;
}

int piped(io::IOStream& link, const ShellClientOptions& o) {
  if (!o.token.empty() && !send(link, o.token + "\n")) return kExitFailure;
  Printer printer(link, o.output_fd);
  std::string pending;
  bool eof = false;
  while (!eof && !printer.closed()) {
    auto in = read_input(o.input_fd, 50ms);
    if (!in) {
      eof = true;
    } else {
      pending += *in;
    }
    // Whole lines only, so that the shell sees each line as it was written.
    const std::size_t last_nl = pending.rfind('\n');
    if (last_nl != std::string::npos) {
      if (!send(link, std::string_view(pending).substr(0, last_nl + 1))) break;
      pending.erase(0, last_nl + 1);
    }
  }
  if (!pending.empty() && !printer.closed()) (void)send(link, pending + "\n");
  // The replies to the last lines may still be on their way: wait until they stop.
  const auto eof_at = Clock::now();
  while (!printer.closed()) {
    const auto now = Clock::now();
    if (now - eof_at >= o.drain_limit) break;
    if (now - eof_at >= o.quiet && now - printer.last_data() >= o.quiet) break;
    std::this_thread::sleep_for(10ms);
  }
  printer.stop();
  return kExitOk;
}

}  // namespace

std::variant<ShellClientOptions, UsageError> parse_shell_client_args(std::span<const std::string_view> args) {
  auto parsed = parse_options(args, kSpecs);
  if (auto* e = std::get_if<UsageError>(&parsed)) return *e;
  ShellClientOptions o;
  bool baud_given = false;
  for (const auto& p : std::get<std::vector<ParsedOption>>(parsed)) {
    if (p.name == "--help") {
      o.help = true;
      return o;
    }
    if (p.name == "--tcp") o.tcp = p.value;
    if (p.name == "--token") o.token = p.value;
    if (p.name == "--serial") o.serial = p.value;
    if (p.name == "--baud") {
      auto b = parse_count("--baud", p.value, 50, 4000000);
      if (auto* e = std::get_if<UsageError>(&b)) return *e;
      o.baud = static_cast<int>(std::get<std::uint64_t>(b));
      baud_given = true;
    }
  }
  if (o.tcp.empty() == o.serial.empty()) return UsageError{"give exactly one of --tcp HOST:PORT and --serial PATH"};
  if (baud_given && o.serial.empty()) return UsageError{"--baud goes with --serial"};
  if (!o.token.empty() && o.token.find_first_of("\r\n") != std::string::npos)
    return UsageError{"--token may not hold a line break"};
  return o;
}

std::string shell_client_help() {
  return "usage: symb shell --tcp HOST:PORT [--token T] | --serial PATH [--baud N]\n"
         "Opens a node's command shell. From a terminal, keys go to the shell as typed and Ctrl-] quits;\n"
         "from a pipe, each line is sent and the replies printed until they stop coming.\n" +
         describe_options(kSpecs);
}

int run_shell_client(const ShellClientOptions& o) {
  std::ostream& err = o.err != nullptr ? *o.err : std::cerr;
  std::shared_ptr<io::IOStream> link;
  const bool tcp = !o.tcp.empty();
  if (tcp) {
    std::string host = o.tcp;
    std::string port_text;
    if (host.starts_with('[')) {  // [::1]:PORT
      const std::size_t close = host.find(']');
      if (close == std::string::npos || close + 1 >= host.size() || host[close + 1] != ':') {
        err << "symb shell: --tcp: expected HOST:PORT, got " << quote_arg(o.tcp) << "\n";
        return kExitUsage;
      }
      port_text = host.substr(close + 2);
      host = host.substr(1, close - 1);
    } else {
      const std::size_t colon = host.rfind(':');
      if (colon == std::string::npos || colon == 0) {
        err << "symb shell: --tcp: expected HOST:PORT, got " << quote_arg(o.tcp) << "\n";
        return kExitUsage;
      }
      port_text = host.substr(colon + 1);
      host.resize(colon);
    }
    auto port = parse_count("--tcp port", port_text, 1, 65535);
    if (auto* e = std::get_if<UsageError>(&port)) {
      err << "symb shell: " << e->message << "\n";
      return kExitUsage;
    }
    auto conn = io::TcpStream::connect(host, static_cast<std::uint16_t>(std::get<std::uint64_t>(port)));
    if (!conn) {
      err << "symb shell: cannot connect to " << o.tcp << ": " << conn.error() << "\n";
      return kExitFailure;
    }
    link = std::move(conn).value();
  } else {
    io::SerialSettings s;
    s.baud = o.baud;
    auto port = std::make_shared<io::SerialPort>("serial", o.serial, s);
    if (auto st = port->open(); !st) {
      err << "symb shell: " << st.error() << "\n";
      return kExitFailure;
    }
    link = port;
  }
  const int rc = ::isatty(o.input_fd) ? interactive(*link, o, err, tcp) : piped(*link, o);
  link->close();
  return rc;
}

}  // namespace symb::apps
