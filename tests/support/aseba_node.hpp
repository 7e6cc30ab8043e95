// FakeAsebaNode: a node that speaks the Aseba protocol, for tests that need one without Aseba
// Playground: it answers list nodes, get node description (its own variable table), get and set
// variables, and echoes user events back as the same event. It serves TCP connections one at a
// time on a local port (like a Playground robot), so a test can cut the link (close()) and bring
// it back on the same port (listen()), or serves one stream (serve()). Memory is a table of words
// the test may read and write (peek/poke) while the node runs.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "symb/io/aseba_message.hpp"
#include "symb/io/stream.hpp"
#include "symb/io/tcp_stream.hpp"

namespace symb::testing {

class FakeAsebaNode {
 public:
  struct Variable {
    std::string name;
    std::uint16_t size;
  };
  // A Thymio II's first variables, in its order (prox.horizontal at 42 and the motors at 57..60
  // as on a real one), in 100 words.
  static std::vector<Variable> thymio_variables() {
    return {{"_id", 1},
            {"event.source", 1},
            {"event.args", 32},
            {"_productId", 1},
            {"_fwversion", 2},
            {"buttons", 5},
            {"prox.horizontal", 7},
            {"prox.comm", 2},
            {"prox.ground.ambiant", 2},
            {"prox.ground.reflected", 2},
            {"prox.ground.delta", 2},
            {"motor.left.target", 1},
            {"motor.right.target", 1},
            {"motor.left.speed", 1},
            {"motor.right.speed", 1}};
  }

  FakeAsebaNode(std::string name = "thymio-II", std::vector<Variable> vars = thymio_variables(), std::uint16_t id = 1,
                std::uint16_t memory = 100)
      : name_(std::move(name)), vars_(std::move(vars)), id_(id), memory_(memory, 0) {}
  ~FakeAsebaNode() { close(); }

  // Listens on 127.0.0.1 (port 0: a free one) and serves connections until close().
  bool listen(std::uint16_t port = 0) {
    auto l = io::TcpListener::bind("127.0.0.1", port);
    if (!l) return false;
    listener_ = std::move(l).value();
    port_ = listener_->port();
    stop_ = false;
    thread_ = std::thread([this] {
      while (!stop_) {
        auto s = listener_->accept(std::chrono::milliseconds(50));
        if (!s) return;
        if (!*s) continue;
        std::shared_ptr<io::IOStream> stream = std::move(s).value();
        {
          std::lock_guard lock(mu_);
          current_ = stream;
        }
        serve(*stream);
      }
    });
    return true;
  }
  // Stops serving and drops the connection (the host sees the end of its stream).
  void close() {
    stop_ = true;
    if (listener_) listener_->close();
    {
      std::lock_guard lock(mu_);
      if (current_) current_->close();
    }
    if (thread_.joinable()) thread_.join();
    listener_.reset();
    std::lock_guard lock(mu_);
    current_.reset();
  }
  std::uint16_t port() const { return port_; }

  // Serves one stream until it ends (on the caller's thread).
  void serve(io::IOStream& s) {
    io::aseba::AsebaDecoder decoder;
    std::vector<std::byte> buf(1024);
    while (!stop_) {
      auto n = s.read_some(buf, std::chrono::milliseconds(50));
      if (!n) return;
      decoder.feed(std::span<const std::byte>(buf.data(), *n), [&](const io::aseba::Message& m) { answer(s, m); });
    }
  }

  std::int16_t peek(std::size_t address) {
    std::lock_guard lock(mu_);
    return memory_.at(address);
  }
  void poke(std::size_t address, std::int16_t v) {
    std::lock_guard lock(mu_);
    memory_.at(address) = v;
  }
  std::uint16_t address_of(const std::string& name) const {
    std::uint16_t a = 0;
    for (const auto& v : vars_) {
      if (v.name == name) return a;
      a = static_cast<std::uint16_t>(a + v.size);
    }
    return 0xFFFF;
  }
  // Answer get variables or not (a node that hangs).
  void set_answering(bool on) { answering_ = on; }
  std::uint64_t sets() const { return sets_; }

 private:
  void send(io::IOStream& s, std::uint16_t type, const io::aseba::AsebaWriter& w) {
    auto wire = w.finish(id_, type);
    if (wire) (void)s.write_all(*wire);
  }
  void answer(io::IOStream& s, const io::aseba::Message& m) {
    using namespace io::aseba;
    AsebaReader r(m.payload);
    if (m.type == type::kListNodes) {
      send(s, type::kNodePresent, AsebaWriter().word(kProtocolVersion));
    } else if (m.type == type::kGetNodeDescription) {
      send(s, type::kDescription,
           AsebaWriter()
               .string(name_)
               .word(kProtocolVersion)
               .word(1534)
               .word(32)
               .word(static_cast<std::uint16_t>(memory_.size()))
               .word(static_cast<std::uint16_t>(vars_.size()))
               .word(0)
               .word(0));
      for (const auto& v : vars_) send(s, type::kNamedVariableDescription, AsebaWriter().word(v.size).string(v.name));
    } else if (m.type == type::kGetVariables && answering_) {
      auto dest = r.word();
      auto start = r.word();
      auto count = r.word();
      if (!dest || !start || !count || *dest != id_ || *start + *count > memory_.size()) return;
      AsebaWriter w;
      w.word(*start);
      {
        std::lock_guard lock(mu_);
        for (std::size_t i = 0; i < *count; ++i) w.word(static_cast<std::uint16_t>(memory_[*start + i]));
      }
      send(s, type::kVariables, w);
    } else if (m.type == type::kSetVariables) {
      auto dest = r.word();
      auto start = r.word();
      if (!dest || !start || *dest != id_) return;
      std::lock_guard lock(mu_);
      for (std::size_t a = *start; r.left() >= 2 && a < memory_.size(); ++a)
        memory_[a] = static_cast<std::int16_t>(*r.word());
      ++sets_;
    } else if (m.is_user_event()) {
      AsebaWriter w;
      while (r.left() >= 2) w.word(*r.word());
      send(s, m.type, w);
    }
  }

  std::string name_;
  std::vector<Variable> vars_;
  std::uint16_t id_;
  std::mutex mu_;
  std::vector<std::int16_t> memory_;
  std::shared_ptr<io::IOStream> current_;
  std::unique_ptr<io::TcpListener> listener_;
  std::uint16_t port_ = 0;
  std::atomic<bool> stop_{false};
  std::atomic<bool> answering_{true};
  std::atomic<std::uint64_t> sets_{0};
  std::thread thread_;
};

}  // namespace symb::testing
