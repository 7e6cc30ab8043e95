// Fuzzes the 2D board on the simulator's frames (sim::HilRobotBoard, `symb board --lockstep`):
// whatever a peer sends on its serial line, the board must answer or count it, never crash,
// hang or let one frame run its node for long. The input is a script, so that the fuzzer reaches
// good frames with any sequence numbers as easily as garbage:
//   op 0: an IR frame, its seq a step from the last one (a byte) or any 24-bit number, its seven
//         values from bytes (some past the sensor's range);
//   op 1: a number frame of 0 to 11 arbitrary floats (NaN, infinities, a wrong count);
//   op 2: up to 31 raw bytes (half frames, zeros, noise);
//   op 3: the board serves what came so far.
// Checked after every serve, on the maze's robot with its MDL2e controller:
//  - every good frame is accounted for: frames + handshakes + restarts + malformed + out of order;
//  - every accepted frame is answered (answers + not taken), and every answer is a wheel frame
//    within +-500;
//  - the node's time never goes back, and no frame moved it more than max_catch_up periods.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "symb/io/frame_codec.hpp"
#include "symb/io/loopback_stream.hpp"
#include "symb/io/stream_task.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/sim/hil_protocol.hpp"
#include "symb/sim/hil_robot_board.hpp"
#include "symb/sim/robot_system.hpp"
#include "symb/sim/scenario.hpp"

using namespace symb;
using namespace symb::sim;

namespace {

constexpr std::uint32_t kMaxCatchUp = 64;

void check(bool ok) {
  if (!ok) std::abort();
}

const Scenario& maze() {
  static const Scenario sc = [] {
    auto loaded = load_scenario(std::string(SYMB_SCENARIO_DIR) + "/maze.yaml");
    check(loaded.ok());
    return std::move(loaded).value();
  }();
  return sc;
}

struct Reader {
  const std::uint8_t* data;
  std::size_t size;
  std::size_t at = 0;
  bool more() const { return at < size; }
  std::uint8_t byte() { return at < size ? data[at++] : 0; }
};

class Rig {
 public:
  Rig() {
    auto [a, b] = io::make_loopback_pair("fuzz-hil", 1 << 20);
    sim_end_ = std::move(a);
    std::shared_ptr<io::IOStream> board_end = std::move(b);
    FrameClockBoardOptions bo;
    bo.control_period = maze().control_period;
    bo.max_catch_up = kMaxCatchUp;
    board_ = std::make_unique<HilRobotBoard>(ex_, board_end, bo);
    RobotSystemOptions ro;
    ro.control_period = maze().control_period;
    ro.read_program = file_program_reader(maze().base_dir);
    auto built = RobotSystem::build(ex_, maze().robots.at(0), board_->devices(), std::move(ro));
    check(built.ok());
    system_ = std::move(built).value();
    check(board_->start().ok());
  }
  ~Rig() {
    system_.reset();
    board_.reset();
  }

  void write(const std::vector<std::byte>& bytes) {
    check(sim_end_->write_all(bytes).ok());
    written_ += bytes.size();
    if (written_ > (1 << 18)) serve();
  }

  // Serves until the line is empty; with `closed`, until the board sees its end.
  void serve(bool closed = false) {
    written_ = 0;
    for (int i = 0; i < 100000; ++i) {
      const kernel::Time before = ex_.now();
      const auto before_stats = board_->stats();
      auto got = board_->serve(closed ? std::chrono::milliseconds(1) : kernel::Duration{0});
      const auto s = board_->stats();
      check(ex_.now() >= before);
      // At most max_catch_up periods a frame.
      const auto frames = static_cast<std::int64_t>(s.frames - before_stats.frames);
      check(ex_.now() - before <= maze().control_period * (frames * kMaxCatchUp + 1));
      check(s.decoder.frames == s.frames + s.handshakes + s.restarts + s.malformed + s.out_of_order);
      check(s.answers + s.write_errors == s.frames + s.handshakes + s.restarts);
      drain_answers();
      if (!got.ok()) {
        check(closed);
        return;
      }
      if (!closed && *got == 0 && s.decoder.bytes == before_stats.decoder.bytes) return;
    }
    check(false);  // the line never ran dry: a livelock
  }

  void close() {
    sim_end_->close();
    serve(true);
  }

 private:
  void drain_answers() {
    std::vector<std::byte> buf(1 << 16);
    for (;;) {
      auto got = sim_end_->read_some(buf, kernel::Duration{0});
      if (!got.ok() || *got == 0) return;
      decoder_.feed(std::span<const std::byte>(buf.data(), *got), [](std::span<const std::byte> p) {
        auto w = decode_wheel_payload(p);
        check(w.ok());
        check(std::isfinite(w->left) && std::isfinite(w->right));
        check(std::fabs(w->left) <= kHilWheelLimit && std::fabs(w->right) <= kHilWheelLimit);
      });
      check(decoder_.stats().dropped() == 0);
    }
  }

  kernel::VirtualTimeExecutor ex_;
  std::unique_ptr<io::IOStream> sim_end_;
  std::unique_ptr<HilRobotBoard> board_;
  std::unique_ptr<RobotSystem> system_;
  io::FrameDecoder decoder_;
  std::size_t written_ = 0;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Rig rig;
  Reader in{data, size};
  std::uint32_t seq = 0;
  while (in.more()) {
    const std::uint8_t op = in.byte();
    switch (op % 4) {
      case 0: {
        if (op & 0x80) {
          seq = static_cast<std::uint32_t>(in.byte()) | static_cast<std::uint32_t>(in.byte()) << 8 |
                static_cast<std::uint32_t>(in.byte()) << 16;
        } else {
          seq += in.byte() % 4;  // mostly the next one, sometimes a repeat or a skip
        }
        if (seq > kHilMaxSequence) seq = kHilMaxSequence;
        HilIrFrame f;
        f.seq = seq;
        for (float& v : f.ir) v = static_cast<float>(in.byte()) * 20.0f;
        rig.write(io::encode_frame(encode_ir_payload(f)));
        break;
      }
      case 1: {
        std::vector<float> v(in.byte() % 12);
        for (float& x : v) {
          std::uint32_t bits = 0;
          for (int k = 0; k < 4; ++k) bits |= static_cast<std::uint32_t>(in.byte()) << (8 * k);
          std::memcpy(&x, &bits, sizeof x);
        }
        rig.write(io::encode_frame(io::encode_numbers(v)));
        break;
      }
      case 2: {
        std::vector<std::byte> raw(in.byte() % 32);
        for (std::byte& b : raw) b = static_cast<std::byte>(in.byte());
        rig.write(raw);
        break;
      }
      default: rig.serve();
    }
  }
  rig.close();
  return 0;
}
