// MemoryLine: a serial line in memory for the board's maze graph off the UART: the self-test image
// and the host benchmark (bench/board_step_bench.cpp) write what a simulator would send into
// `in` and read what the board sent from `out`. Fixed buffers: no heap once made.
#pragma once

#include <algorithm>
#include <array>
#include <cstring>

#include "symb/io/stream.hpp"

namespace symb::board {

class MemoryLine final : public io::IOStream {
 public:
  MemoryLine() : Device("uart0"), IOStream("uart0") {}
  kernel::Status open() override { return {}; }
  void close() override {}
  bool is_open() const override { return true; }
  kernel::Result<std::size_t> read_some(std::span<std::byte> buf, kernel::Duration) override {
    const std::size_t n = std::min(buf.size(), in_size - in_pos);
    std::memcpy(buf.data(), in.data() + in_pos, n);
    in_pos += n;
    return n;
  }
  kernel::Status write_all(std::span<const std::byte> data) override {
    if (out_size + data.size() > out.size()) return kernel::Error{"full"};
    std::memcpy(out.data() + out_size, data.data(), data.size());
    out_size += data.size();
    return {};
  }
  std::array<std::byte, 512> in{};
  std::size_t in_size = 0, in_pos = 0;
  std::array<std::byte, 512> out{};
  std::size_t out_size = 0;
};

}  // namespace symb::board
