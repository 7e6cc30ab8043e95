// Fuzzes the command shell: arbitrary bytes as one line through the tokenizer and Shell::execute,
// and as a byte stream through the line editor (plain and terminal mode) whose lines are executed
// in turn, against a small node under virtual time (two task types, a few tasks and hooks, a
// device). Any input must give replies that keep the shell's contract (an error's text starts with
// "error: ", every reply ends with a newline) and never crash, hang or trip a sanitizer. `run`
// reads scripts from memory: "self" is the input itself.
#include <cstdint>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <string_view>

#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/shell/command_line.hpp"
#include "symb/shell/line_editor.hpp"
#include "symb/shell/shell.hpp"
#include "symb/shell/shell_task.hpp"

using namespace symb;

namespace {

class Ticker : public os::Task {
 protected:
  void on_tick() override { send(0, {1.0f, 2.0f}); }
};

class Knob final : public io::Device {
 public:
  Knob() : Device("knob") {
    add_ioctl({"level", os::ParamSpec{"level", os::ParamType::kReal, 0.0, 0.0, 10.0, ""}, "set"},
              [](const os::ParamValue*) -> kernel::Result<std::string> { return std::string("set"); });
    add_ioctl({"info", std::nullopt, "show"},
              [](const os::ParamValue*) -> kernel::Result<std::string> { return std::string("knob"); });
  }
  kernel::Status open() override { return {}; }
  void close() override {}
  bool is_open() const override { return true; }
};

void check(const shell::Reply& r) {
  if (!r.ok && !r.text.starts_with("error: ")) std::abort();
  if (!r.text.empty() && r.text.back() != '\n') std::abort();
  if (!r.ok && r.text.size() < 8) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  static const os::TaskTypeRegistry* types = [] {
    auto* r = new os::TaskTypeRegistry;
    os::TaskType t;
    t.name = "ticker";
    t.params = {{"gain", os::ParamType::kReal, 1.0, -10.0, 10.0, ""},
                {"name", os::ParamType::kString, std::string("x"), std::nullopt, 16.0, ""},
                {"every", os::ParamType::kDuration, kernel::Duration{1000000}, 0.001, 1.0, ""}};
    t.defaults.period = kernel::Duration{10'000'000};
    t.make = [](const os::ParamSet&) { return std::unique_ptr<os::Task>(std::make_unique<Ticker>()); };
    (void)r->add(t);
    os::TaskType s;
    s.name = "sink";
    s.make = [](const os::ParamSet&) { return std::unique_ptr<os::Task>(std::make_unique<Ticker>()); };
    (void)r->add(s);
    (void)shell::register_shell_types(*r);
    return r;
  }();

  (void)shell::tokenize(input);

  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {"fuzz", 1, 64, types});
  std::vector<os::ParamAssignment> none;
  auto a = node.create("ticker", "a", none);
  auto b = node.create("sink", "b", none);
  if (!a || !b) std::abort();
  (void)node.hook(*a, *b);
  auto devices = std::make_shared<shell::DeviceTable>();
  (*devices)["knob"] = std::make_shared<Knob>();
  shell::Shell::Options options;
  options.devices = devices;
  options.max_script_lines = 2000;
  options.read_file = [&input](const std::string& path) -> kernel::Result<std::string> {
    if (path == "self") return input;
    return kernel::Error{"no such file"};
  };
  shell::Shell sh(node, options);

  check(sh.execute(input));
  ex.run_for(kernel::Duration{30'000'000});

  for (bool terminal : {false, true}) {
    shell::LineEditor editor({terminal, shell::kMaxLineBytes, 8, "> "});
    std::vector<shell::EditorEvent> events;
    (void)editor.feed(input, events);
    if (editor.buffer().size() > shell::kMaxLineBytes) std::abort();
    for (const auto& e : events) {
      if (e.kind != shell::EditorEvent::Kind::kLine) continue;
      if (e.text.size() > shell::kMaxLineBytes) std::abort();
      check(sh.execute(e.text));
    }
    (void)editor.redraw();
    ex.run_for(kernel::Duration{30'000'000});
  }
  (void)sh.follow_output();
  return 0;
}
