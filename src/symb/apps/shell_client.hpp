// `symb shell`: a small terminal client (picocom- or telnet-like) for a node's command shell, over
// TCP (`--tcp HOST:PORT [--token T]`, a TcpShellServer) or a serial line (`--serial PATH
// [--baud N]`, a board's shell UART or a pseudo-terminal).
//  - From a terminal: stdin goes into raw mode (restored on exit, and on SIGINT, SIGTERM and
//    SIGHUP), every keystroke is forwarded and everything that comes back is printed; the shell at
//    the other end echoes and edits the line (over TCP the client asks for that with telnet's
//    IAC DO ECHO). Ctrl-] quits.
//  - From a pipe or a file: stdin is sent line by line and the replies printed; after the end of
//    input the client waits until the replies have stopped coming (a short quiet period), then
//    exits. That makes `symb shell --tcp ... < script` usable from scripts.
// A token given with --token is sent as the first line.
#pragma once

#include <chrono>
#include <cstdint>
#include <ostream>
#include <span>
#include <string>
#include <string_view>
#include <variant>

#include "symb/apps/cli_args.hpp"

namespace symb::apps {

struct ShellClientOptions {
  std::string tcp;     // HOST:PORT ([::1]:PORT for IPv6); exclusive with serial
  std::string token;   // sent as the first line when not empty
  std::string serial;  // a serial device or pseudo-terminal path
  int baud = 115200;
  int input_fd = 0;             // what is typed or piped in
  int output_fd = 1;            // where replies go
  std::ostream* err = nullptr;  // messages; null: std::cerr
  // Piped input: how long the replies must have been quiet after the end of input, and the most
  // the client waits for them altogether.
  std::chrono::milliseconds quiet{300};
  std::chrono::milliseconds drain_limit{10000};
  bool help = false;  // -h or --help was given: print shell_client_help() instead of running
};

// Reads `symb shell` arguments (what follows "shell"): exactly one of --tcp and --serial, unless
// --help.
std::variant<ShellClientOptions, UsageError> parse_shell_client_args(std::span<const std::string_view> args);
// The help text of `symb shell`.
std::string shell_client_help();

// Runs the client until Ctrl-], the end of piped input, or the other end closing. Returns kExitOk,
// kExitFailure when it cannot connect or open the device (with a message), or kExitUsage for
// options that make no sense (an address without a port).
int run_shell_client(const ShellClientOptions& options);

}  // namespace symb::apps
