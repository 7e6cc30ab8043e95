#include "symb/os/syslog.hpp"

#include <sstream>

#include <gtest/gtest.h>

namespace symb::os {
namespace {

TEST(SysLog, KeepsTheNewestEntriesWithSequenceNumbers) {
  kernel::VirtualClock clock;
  SysLog log(clock, 3);
  for (int i = 1; i <= 5; ++i) {
    clock.advance_to(kernel::Time{i * 1000000});
    log.info("t", "entry " + std::to_string(i));
  }
  auto all = log.since(0);
  ASSERT_EQ(all.size(), 3u);
  EXPECT_EQ(all[0].seq, 3u);
  EXPECT_EQ(all[0].text, "entry 3");
  EXPECT_EQ(all[0].time, kernel::Time{3000000});
  EXPECT_EQ(log.overwritten(), 2u);
  EXPECT_EQ(log.last_seq(), 5u);
  auto after4 = log.since(4);
  ASSERT_EQ(after4.size(), 1u);
  EXPECT_EQ(after4[0].text, "entry 5");
  EXPECT_TRUE(log.since(5).empty());
}

TEST(SysLog, LevelFilterAndSinks) {
  kernel::VirtualClock clock;
  SysLog log(clock, 10);
  std::ostringstream out;
  auto sink = std::make_shared<OstreamLogSink>(out);
  log.add_sink(sink);
  log.set_level(LogLevel::kWarn);
  log.info("a", "hidden");
  log.warn("a", "shown");
  log.remove_sink(sink);
  log.error("a", "not in the sink");
  EXPECT_EQ(out.str(), "[     0.000000] WARN  a: shown\n");
  EXPECT_EQ(log.since(0).size(), 2u);
}

TEST(SysLog, BoundsTextAndNeutralisesControlCharacters) {
  kernel::VirtualClock clock;
  SysLog log(clock, 2);
  log.info("a", std::string(10000, 'x'));
  log.info("a", "line1\nFAKE ENTRY\x1b[31m");
  auto e = log.since(0);
  EXPECT_EQ(e[0].text.size(), SysLog::kMaxText);
  EXPECT_EQ(e[1].text.find('\n'), std::string::npos);
  EXPECT_EQ(e[1].text.find('\x1b'), std::string::npos);
}

}  // namespace
}  // namespace symb::os
