// AEDAT 2.0 files: the header and records as jAER writes them, round trips through bytes and a
// real temporary file (bit-identical events, same comments), and malformed files rejected with
// located errors ("LINE:COLUMN: " in the header, "byte OFFSET: " in the records).
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/snn/aedat.hpp"
#include "symb/kernel/random_stream.hpp"

namespace symb::control::snn {
namespace {

std::vector<AerEvent> random_aedat_events(std::size_t n, std::uint64_t seed) {
  kernel::RandomStream r(seed);
  std::vector<AerEvent> e(n);
  std::uint32_t t = 0;
  for (auto& x : e) {
    x.address = aer_address(static_cast<std::uint32_t>(r.below(kMaxModule + 1)),
                            static_cast<std::uint32_t>(r.below(kMaxNeuronAddress + 1)));
    t += static_cast<std::uint32_t>(r.below(5000));
    x.timestamp_us = t;
  }
  return e;
}

void expect_error_starts(const kernel::Result<AedatFile>& r, const std::string& prefix) {
  ASSERT_FALSE(r.ok()) << "expected an error starting " << prefix;
  EXPECT_EQ(r.error().rfind(prefix, 0), 0u) << r.error();
}

TEST(AedatWriter, HeaderAndRecordsAreJaerLayout) {
  const std::vector<std::string> comments{"symb run maze", "line\r\ncut here", "tab\tkept"};
  std::string f = aedat_header(comments);
  EXPECT_EQ(f, "#!AER-DAT2.0\r\n# symb run maze\r\n# line\r\n# tab\tkept\r\n");
  const std::vector<AerEvent> e{{0x01020304u, 0x0A0B0C0Du}};
  append_aedat_records(f, e);
  const std::string tail = f.substr(f.size() - 8);
  EXPECT_EQ(tail, std::string("\x01\x02\x03\x04\x0A\x0B\x0C\x0D", 8));
  EXPECT_EQ(aedat_header({}), "#!AER-DAT2.0\r\n");
}

TEST(AedatReader, RoundTripIsBitIdentical) {
  const std::vector<std::string> comments{"Symbricator spike raster", "", "  indented", "module 3 = linda"};
  for (std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{20000}}) {
    const auto events = random_aedat_events(n, n + 5);
    std::string f = aedat_header(comments);
    // Records may be appended in pieces, as a run writes them.
    append_aedat_records(f, std::span(events).first(n / 2));
    append_aedat_records(f, std::span(events).subspan(n / 2));
    auto r = read_aedat(f);
    ASSERT_TRUE(r.ok()) << r.error();
    EXPECT_EQ(r->header, comments);
    EXPECT_TRUE(r->events == events) << n;
    std::string again = aedat_header(r->header);
    append_aedat_records(again, r->events);
    EXPECT_EQ(again, f);
  }
}

TEST(AedatReader, RecordsStartingWithHashAfterTheHeaderAreData) {
  // The header ends at the first line not starting with '#'; a record whose first byte is '#'
  // right after the header would be read as a header line (AEDAT 2.0's own ambiguity), so
  // records are checked after a record starting otherwise.
  std::string f = aedat_header({});
  append_aedat_records(f, std::vector<AerEvent>{{aer_address(1, 0), 0}, {aer_address('#', 1), 2}});
  auto r = read_aedat(f);
  ASSERT_TRUE(r.ok()) << r.error();
  ASSERT_EQ(r->events.size(), 2u);
  EXPECT_EQ(aer_module(r->events[1].address), static_cast<std::uint32_t>('#'));
  // The first record must not start with '#' (module 35): jAER would take it for a header line,
  // and so does this reader, which then finds no "\r\n" and says where.
  std::string g = aedat_header({});
  append_aedat_records(g, std::vector<AerEvent>{{aer_address('#', 1), 2}});
  expect_error_starts(read_aedat(g), "2:9: ");
}

TEST(AedatReader, JaerStyleHeaderIsRead) {
  const std::string f =
      "#!AER-DAT2.0\r\n# This is a raw AE data file - do not edit\r\n# Data format is int32 address, int32 "
      "timestamp (8 bytes total), repeated for each event\r\n#Timestamps tick is 1 us\r\n" +
      std::string("\x00\x00\x00\x05\x00\x00\x00\x07", 8);
  auto r = read_aedat(f);
  ASSERT_TRUE(r.ok()) << r.error();
  ASSERT_EQ(r->header.size(), 3u);
  EXPECT_EQ(r->header[2], "Timestamps tick is 1 us");
  ASSERT_EQ(r->events.size(), 1u);
  EXPECT_EQ(r->events[0], (AerEvent{5, 7}));
}

TEST(AedatReader, RoundTripThroughARealFile) {
  const auto events = random_aedat_events(5000, 77);
  std::string f = aedat_header(std::vector<std::string>{"written by snn_aedat_test"});
  append_aedat_records(f, events);
  const auto path = std::filesystem::temp_directory_path() /
                    ("symb_aedat_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
                     std::to_string(reinterpret_cast<std::uintptr_t>(&f)) + ".aedat");
  {
    std::ofstream out(path, std::ios::binary);
    ASSERT_TRUE(out) << path;
    out.write(f.data(), static_cast<std::streamsize>(f.size()));
  }
  std::string back;
  {
    std::ifstream in(path, std::ios::binary);
    ASSERT_TRUE(in) << path;
    back.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  std::filesystem::remove(path);
  EXPECT_EQ(std::filesystem::exists(path), false);
  ASSERT_EQ(back.size(), f.size());
  auto r = read_aedat(back);
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->header, std::vector<std::string>{"written by snn_aedat_test"});
  EXPECT_TRUE(r->events == events);
}

TEST(AedatReader, MalformedFilesGetLocatedErrors) {
  expect_error_starts(read_aedat(""), "1:1: ");
  // No version line: records only, or a plain comment first.
  expect_error_starts(read_aedat(std::string("\x00\x00\x00\x01\x00\x00\x00\x02", 8)), "1:1: ");
  expect_error_starts(read_aedat("# comment\r\n"), "1:2: ");
  // Another version: the column where it differs.
  auto v3 = read_aedat("#!AER-DAT3.1\r\n");
  expect_error_starts(v3, "1:10: ");
  EXPECT_NE(v3.error().find("3.1"), std::string::npos) << v3.error();
  expect_error_starts(read_aedat("#!AER-DAT2.01\r\n"), "1:13: ");
  // Header lines without "\r\n": a bare "\n", or the file ends inside the line.
  expect_error_starts(read_aedat("#!AER-DAT2.0\n"), "1:13: ");
  expect_error_starts(read_aedat("#!AER-DAT2.0"), "1:13: ");
  expect_error_starts(read_aedat("#!AER-DAT2.0\r\n# ok\r\n# bad\n"), "3:6: ");
  expect_error_starts(read_aedat("#!AER-DAT2.0\r\n# ok\r\n# unfinished"), "3:13: ");
  expect_error_starts(read_aedat("#!AER-DAT2.0\r\n# a\rb\r\n"), "2:4: ");
  // A trailing partial record: the offset of its first byte.
  std::string f = aedat_header({});  // 14 bytes
  append_aedat_records(f, std::vector<AerEvent>{{1, 2}, {3, 4}});
  f += "\x01\x02\x03";
  expect_error_starts(read_aedat(f), "byte 30: ");
  expect_error_starts(read_aedat("#!AER-DAT2.0\r\n\x05"), "byte 14: ");
}

TEST(AedatReader, HeaderOnlyIsValid) {
  auto r = read_aedat("#!AER-DAT2.0\r\n");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_TRUE(r->header.empty());
  EXPECT_TRUE(r->events.empty());
}

TEST(AedatReader, RandomMutationsNeverCrash) {
  kernel::RandomStream r(11);
  std::string base = aedat_header(std::vector<std::string>{"a", "bb"});
  append_aedat_records(base, random_aedat_events(20, 3));
  std::size_t accepted = 0;
  for (int i = 0; i < 1000; ++i) {
    std::string f = base.substr(0, r.below(base.size() + 1));
    for (std::uint64_t k = r.below(4); k > 0 && !f.empty(); --k) f[r.below(f.size())] = static_cast<char>(r.below(256));
    // An exactly sized heap copy, so a read past the end shows under ASan.
    const std::vector<char> exact(f.begin(), f.end());
    auto a = read_aedat(std::string_view(exact.data(), exact.size()));
    if (a) {
      ++accepted;
      std::string again = aedat_header(a->header);
      append_aedat_records(again, a->events);
      EXPECT_LE(again.size(), f.size() + 2 * a->header.size()) << "the writer's \"# \" may add a space per line";
    } else {
      const std::string& e = a.error();
      const bool located = e.rfind("byte ", 0) == 0 || (!e.empty() && std::isdigit(static_cast<unsigned char>(e[0])) &&
                                                        e.find(':') != std::string::npos);
      EXPECT_TRUE(located) << e;
    }
  }
  EXPECT_GT(accepted, 0u);
}

}  // namespace
}  // namespace symb::control::snn
