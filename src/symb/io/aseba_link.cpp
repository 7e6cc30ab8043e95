#include "symb/io/aseba_link.hpp"

#include <chrono>
#include <cstdio>

namespace symb::io::aseba {

namespace {

using Clock = std::chrono::steady_clock;

kernel::Duration left_until(Clock::time_point deadline) {
  const auto left = deadline - Clock::now();
  return left.count() > 0 ? std::chrono::duration_cast<kernel::Duration>(left) : kernel::Duration{0};
}

}  // namespace

std::string describe(const LinkStats& s) {
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "%llu messages, %llu refused (oversized %llu, malformed %llu, bad address %llu), %llu unasked, "
                "%llu ignored, %llu events; %llu requests, %llu replies, %llu timeouts; %llu writes, %llu failed",
                static_cast<unsigned long long>(s.decoder.messages), static_cast<unsigned long long>(s.refused()),
                static_cast<unsigned long long>(s.decoder.oversized), static_cast<unsigned long long>(s.malformed),
                static_cast<unsigned long long>(s.bad_address), static_cast<unsigned long long>(s.unasked),
                static_cast<unsigned long long>(s.ignored), static_cast<unsigned long long>(s.user_events),
                static_cast<unsigned long long>(s.requests), static_cast<unsigned long long>(s.replies),
                static_cast<unsigned long long>(s.timeouts), static_cast<unsigned long long>(s.writes),
                static_cast<unsigned long long>(s.write_errors));
  return buf;
}

AsebaLink::AsebaLink(std::shared_ptr<IOStream> stream, std::size_t max_payload)
    : stream_(std::move(stream)), decoder_(max_payload), buffer_(4096) {}

kernel::Status AsebaLink::write(std::span<const std::byte> wire) {
  kernel::Status st;
  {
    std::lock_guard lock(write_mu_);
    st = stream_->is_open() ? stream_->write_all(wire)
                            : kernel::Status(kernel::Error{"aseba: '" + stream_->name() + "' is not open"});
  }
  count([&](LinkStats& s) { ++(st ? s.writes : s.write_errors); });
  return st;
}

template <class On>
kernel::Status AsebaLink::read_once(kernel::Duration timeout, On&& on) {
  auto n = stream_->read_some(buffer_, timeout);
  if (!n) return kernel::Error{"aseba: '" + stream_->name() + "': " + n.error()};
  decoder_.feed(std::span<const std::byte>(buffer_.data(), *n), [&](const Message& m) {
    if (!on(m)) handle_unclaimed(m);
  });
  count([&](LinkStats& s) { s.decoder = decoder_.stats(); });
  return {};
}

void AsebaLink::handle_unclaimed(const Message& m) {
  if (m.is_user_event()) {
    auto args = read_event_args(m);
    if (!args) {
      count([](LinkStats& s) { ++s.malformed; });
      return;
    }
    count([](LinkStats& s) { ++s.user_events; });
    if (on_event_) on_event_(m.source, m.type, *args);
    return;
  }
  if (m.type == type::kVariables) {
    count([](LinkStats& s) { ++s.unasked; });
    return;
  }
  count([](LinkStats& s) { ++s.ignored; });
}

kernel::Result<std::uint16_t> AsebaLink::discover(kernel::Duration timeout) {
  if (auto st = write(list_nodes()); !st) return kernel::Error{st.error()};
  const auto deadline = Clock::now() + timeout;
  std::optional<std::uint16_t> found;
  while (!found) {
    const kernel::Duration left = left_until(deadline);
    if (left.count() == 0) break;
    auto st = read_once(left, [&](const Message& m) {
      if (m.type != type::kNodePresent) return false;
      if (!read_node_present(m)) {
        count([](LinkStats& s) { ++s.malformed; });
        return true;
      }
      if (!found) found = m.source;
      return true;
    });
    if (!st) return kernel::Error{st.error()};
  }
  if (!found)
    return kernel::Error{"aseba: no node answered 'list nodes' on '" + stream_->name() + "' within " +
                         std::to_string(kernel::to_milliseconds(timeout)) + " ms"};
  return *found;
}

kernel::Result<NodeDescription> AsebaLink::describe(std::uint16_t node, kernel::Duration timeout) {
  if (auto st = write(get_node_description(node)); !st) return kernel::Error{st.error()};
  DescriptionBuilder builder(node);
  const auto deadline = Clock::now() + timeout;
  while (!builder.complete() && builder.error().empty()) {
    const kernel::Duration left = left_until(deadline);
    if (left.count() == 0) break;
    auto st = read_once(left, [&](const Message& m) {
      if (!builder.take(m)) return false;
      if (!builder.error().empty()) count([](LinkStats& s) { ++s.malformed; });
      return true;
    });
    if (!st) return kernel::Error{st.error()};
  }
  if (!builder.error().empty())
    return kernel::Error{"aseba: node " + std::to_string(node) + "'s description refused: " + builder.error()};
  if (!builder.complete())
    return kernel::Error{"aseba: node " + std::to_string(node) + " did not describe itself within " +
                         std::to_string(kernel::to_milliseconds(timeout)) + " ms (" +
                         std::to_string(builder.description().variables.size()) + " variables arrived)"};
  return builder.description();
}

kernel::Result<std::vector<std::int16_t>> AsebaLink::get(const NodeDescription& node, std::uint16_t start,
                                                         std::uint16_t count_words, kernel::Duration timeout) {
  if (count_words == 0 || !node.holds(start, count_words))
    return kernel::Error{"aseba: " + std::to_string(count_words) + " words at " + std::to_string(start) +
                         " are outside node " + std::to_string(node.node) + "'s " +
                         std::to_string(node.variables_size) + " words"};
  if (count_words > (kMaxPayload - 2) / 2)
    return kernel::Error{"aseba: " + std::to_string(count_words) + " words do not fit one reply"};
  if (auto st = write(get_variables(node.node, start, count_words)); !st) return kernel::Error{st.error()};
  count([](LinkStats& s) { ++s.requests; });
  const auto deadline = Clock::now() + timeout;
  std::optional<std::vector<std::int16_t>> got;
  while (!got) {
    const kernel::Duration left = left_until(deadline);
    if (left.count() == 0) break;
    auto st = read_once(left, [&](const Message& m) {
      if (m.type != type::kVariables) return false;
      auto v = read_variables(m);
      if (!v) {
        count([](LinkStats& s) { ++s.malformed; });
        return true;
      }
      if (m.source == node.node && !node.holds(v->start, static_cast<std::uint32_t>(v->values.size()))) {
        count([](LinkStats& s) { ++s.bad_address; });
        return true;
      }
      if (got || m.source != node.node || v->start != start || v->values.size() != count_words) return false;
      got = std::move(v->values);
      return true;
    });
    if (!st) return kernel::Error{st.error()};
  }
  if (!got) {
    count([](LinkStats& s) { ++s.timeouts; });
    return kernel::Error{"aseba: node " + std::to_string(node.node) + " did not answer get variables (" +
                         std::to_string(count_words) + " at " + std::to_string(start) + ") within " +
                         std::to_string(kernel::to_milliseconds(timeout)) + " ms"};
  }
  count([](LinkStats& s) { ++s.replies; });
  return std::move(*got);
}

kernel::Status AsebaLink::set(const NodeDescription& node, std::uint16_t start, std::span<const std::int16_t> values) {
  if (values.empty() || !node.holds(start, static_cast<std::uint32_t>(values.size())))
    return kernel::Error{"aseba: " + std::to_string(values.size()) + " words at " + std::to_string(start) +
                         " are outside node " + std::to_string(node.node) + "'s " +
                         std::to_string(node.variables_size) + " words"};
  auto wire = set_variables(node.node, start, values);
  if (!wire) return kernel::Error{wire.error()};
  return write(*wire);
}

kernel::Status AsebaLink::emit(std::uint16_t event, std::span<const std::int16_t> args) {
  auto wire = user_event(event, args);
  if (!wire) return kernel::Error{wire.error()};
  return write(*wire);
}

kernel::Status AsebaLink::pump(kernel::Duration timeout) {
  return read_once(timeout, [](const Message&) { return false; });
}

void AsebaLink::reset() { decoder_.reset(); }

LinkStats AsebaLink::stats() const {
  std::lock_guard lock(stats_mu_);
  return stats_;
}

}  // namespace symb::io::aseba
