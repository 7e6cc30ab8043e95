// The `symb` executable: hands argv and the standard streams to run_symb(). Everything else
// lives in the symb_apps library, where tests can reach it.
#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <string_view>
#include <vector>

#include "symb/apps/symb_cli.hpp"

int main(int argc, char** argv) {
  std::vector<std::string_view> args;
  for (int i = 1; i < argc; ++i) args.emplace_back(argv[i]);
  const symb::apps::CliContext ctx{std::cout, std::cerr, isatty(fileno(stderr)) == 1};
  try {
    return symb::apps::run_symb(args, ctx);
  } catch (const std::exception& e) {
    // Out of memory, a thread the system would not give: say so instead of aborting.
    std::cerr << "symb: " << e.what() << "\n";
    return symb::apps::kExitFailure;
  }
}
