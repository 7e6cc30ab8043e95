#include "symb/os/param.hpp"

#include <gtest/gtest.h>

namespace symb::os {
namespace {

using namespace std::chrono_literals;

ParamSpec real_spec() { return {"gain", ParamType::kReal, 1.0, -2.0, 2.0, "gain"}; }

TEST(Param, ParsesEachType) {
  EXPECT_EQ(std::get<double>(*parse_param_value(real_spec(), "-1.5")), -1.5);
  ParamSpec i{"n", ParamType::kInt, std::int64_t{0}, 0.0, 100.0, ""};
  EXPECT_EQ(std::get<std::int64_t>(*parse_param_value(i, "42")), 42);
  ParamSpec b{"on", ParamType::kBool, false, {}, {}, ""};
  EXPECT_TRUE(std::get<bool>(*parse_param_value(b, "yes")));
  EXPECT_FALSE(std::get<bool>(*parse_param_value(b, "off")));
  ParamSpec d{"period", ParamType::kDuration, kernel::Duration{30ms}, 0.0, 10.0, ""};
  EXPECT_EQ(std::get<kernel::Duration>(*parse_param_value(d, "30ms")), kernel::Duration{30ms});
  EXPECT_EQ(std::get<kernel::Duration>(*parse_param_value(d, "1.5s")), kernel::Duration{1500ms});
  EXPECT_EQ(std::get<kernel::Duration>(*parse_param_value(d, "250us")), kernel::Duration{250us});
  ParamSpec s{"label", ParamType::kString, std::string("x"), 1.0, 8.0, ""};
  EXPECT_EQ(std::get<std::string>(*parse_param_value(s, "hello")), "hello");
}

TEST(Param, RejectsBadTextWithTheParameterName) {
  for (const char* bad : {"", "abc", "1.5x", "nan", "inf", "1e999", "+1", " 1"}) {
    auto r = parse_param_value(real_spec(), bad);
    ASSERT_FALSE(r) << bad;
    EXPECT_NE(r.error().find("'gain'"), std::string::npos) << r.error();
  }
  ParamSpec d{"period", ParamType::kDuration, kernel::Duration{0}, {}, {}, ""};
  for (const char* bad : {"30", "ms", "-1ms", "1e30s", "3 ms", "5d"}) EXPECT_FALSE(parse_param_value(d, bad)) << bad;
  ParamSpec i{"n", ParamType::kInt, std::int64_t{0}, {}, {}, ""};
  for (const char* bad : {"1.0", "99999999999999999999", "0x10", "1 "}) EXPECT_FALSE(parse_param_value(i, bad)) << bad;
}

TEST(Param, RangeErrorsSayTheRange) {
  auto r = parse_param_value(real_spec(), "3");
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("outside [-2, 2]"), std::string::npos) << r.error();
  ParamSpec s{"label", ParamType::kString, std::string("x"), 1.0, 3.0, ""};
  EXPECT_FALSE(parse_param_value(s, "toolong"));
}

TEST(Param, FormatReadsBackToTheSameValue) {
  const std::vector<std::pair<ParamSpec, ParamValue>> cases = {
      {real_spec(), 0.1},
      {real_spec(), -1.0 / 3.0},
      {{"d", ParamType::kDuration, kernel::Duration{0}, {}, {}, ""}, kernel::Duration{1234567}},
      {{"d", ParamType::kDuration, kernel::Duration{0}, {}, {}, ""}, kernel::Duration{30ms}},
      {{"n", ParamType::kInt, std::int64_t{0}, {}, {}, ""}, std::int64_t{-7}},
      {{"b", ParamType::kBool, false, {}, {}, ""}, true}};
  for (const auto& [spec, v] : cases) {
    auto back = parse_param_value(spec, format_param_value(v));
    ASSERT_TRUE(back) << back.error();
    EXPECT_EQ(*back, v) << format_param_value(v);
  }
}

TEST(Param, AssignmentsWithQuotesAndColumns) {
  auto r = parse_param_assignments(R"(gain=1.5  label="two words" esc="a\"b\\c")");
  ASSERT_TRUE(r) << r.error();
  ASSERT_EQ(r->size(), 3u);
  EXPECT_EQ((*r)[0].name, "gain");
  EXPECT_EQ((*r)[0].value, "1.5");
  EXPECT_EQ((*r)[0].column, 1u);
  EXPECT_EQ((*r)[1].value, "two words");
  EXPECT_EQ((*r)[1].column, 11u);
  EXPECT_EQ((*r)[2].value, "a\"b\\c");
  EXPECT_TRUE(parse_param_assignments("")->empty());
}

TEST(Param, AssignmentErrorsGiveTheColumn) {
  struct Case {
    const char* text;
    const char* column;
  };
  for (const auto& c :
       {Case{"gain", "column 1"}, Case{"a=1 b", "column 5"}, Case{"a=1 9x=2", "column 5"}, Case{"a=\"open", "column 3"},
        Case{"a=\"x\"y", "column 6"}, Case{"a=b\"c", "column 4"}, Case{"a=\"\\q\"", "column 4"}}) {
    auto r = parse_param_assignments(c.text);
    ASSERT_FALSE(r) << c.text;
    EXPECT_NE(r.error().find(c.column), std::string::npos) << c.text << " -> " << r.error();
  }
}

TEST(Param, NamesAndHints) {
  EXPECT_TRUE(is_valid_name("wheel.left-2"));
  EXPECT_FALSE(is_valid_name("2wheels"));
  EXPECT_FALSE(is_valid_name(""));
  EXPECT_FALSE(is_valid_name(std::string(64, 'a')));
  EXPECT_FALSE(is_valid_name("a b"));
  std::vector<std::string_view> names = {"gain", "period", "threshold"};
  EXPECT_EQ(closest_name("gian", names), "gain");
  EXPECT_EQ(closest_name("treshold", names), "threshold");
  EXPECT_EQ(closest_name("zzzz", names), "");
}

}  // namespace
}  // namespace symb::os
