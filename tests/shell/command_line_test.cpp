// The tokenizer (words, quotes, comments, columns, refused lines), the option helpers and the
// two output formats (aligned tables, always-valid JSON).
#include "symb/shell/command_line.hpp"

#include <limits>

#include <gtest/gtest.h>

#include "symb/shell/json_writer.hpp"
#include "symb/shell/table.hpp"

#include "shell_test_support.hpp"

namespace symb::shell {
namespace {

using namespace std::chrono_literals;

std::vector<std::string> texts(const std::vector<Token>& tokens) {
  std::vector<std::string> out;
  for (const auto& t : tokens) out.push_back(t.text);
  return out;
}

TEST(Tokenizer, WordsQuotesAndColumns) {
  auto t = tokenize("  create  emitter \"a b\" 'c d' x=1\t# a comment");
  ASSERT_TRUE(t) << t.error();
  EXPECT_EQ(texts(*t), (std::vector<std::string>{"create", "emitter", "a b", "c d", "x=1"}));
  std::vector<std::size_t> columns;
  for (const auto& k : *t) columns.push_back(k.column);
  EXPECT_EQ(columns, (std::vector<std::size_t>{3, 11, 19, 25, 31}));
  EXPECT_FALSE((*t)[0].quoted);
  EXPECT_TRUE((*t)[2].quoted);
}

TEST(Tokenizer, EscapesAndJoinedQuotes) {
  auto t = tokenize(R"(a"b \"c\" \\ \n"d 'x\y' speed="1 2")");
  ASSERT_TRUE(t) << t.error();
  EXPECT_EQ(texts(*t), (std::vector<std::string>{"ab \"c\" \\ \nd", "x\\y", "speed=1 2"}));
  EXPECT_EQ((*t)[2].column, 25u);
}

TEST(Tokenizer, EmptyAndCommentLinesGiveNothing) {
  for (const char* line : {"", "   ", "\t", "# just a comment", "   #x"}) {
    auto t = tokenize(line);
    ASSERT_TRUE(t) << line;
    EXPECT_TRUE(t->empty()) << line;
  }
  auto t = tokenize("a#b # c");
  ASSERT_TRUE(t);
  EXPECT_EQ(texts(*t), (std::vector<std::string>{"a#b"}));  // '#' starts a comment only at a word's start
  auto e = tokenize("\"\" ''");
  ASSERT_TRUE(e);
  EXPECT_EQ(texts(*e), (std::vector<std::string>{"", ""}));
}

TEST(Tokenizer, ErrorsGiveTheColumn) {
  const std::pair<std::string, std::string> cases[] = {
      {"say \"hello", "column 5: unterminated double quote"},
      {"say 'hello", "column 5: unterminated single quote"},
      {"abc\x01", "column 4: control character 0x01"},
      {"ab\x7f", "column 3: control character 0x7f"},
      {std::string("a\0b", 3), "column 2: control character 0x00"},
      {"tasks\r", "column 6: control character 0x0d"},
      {"x \"a\\qb\"", "column 5: unknown escape '\\q'"},
      {"caf\xc3", "column 4: invalid UTF-8"},
      {"a \xff", "column 3: invalid UTF-8"},
      {"\xc0\xaf", "column 1: invalid UTF-8"},          // overlong '/'
      {"x\xed\xa0\x80", "column 2: invalid UTF-8"},     // a surrogate
      {"\xf4\x90\x80\x80", "column 1: invalid UTF-8"},  // past U+10FFFF
  };
  for (const auto& [line, message] : cases) {
    auto t = tokenize(line);
    ASSERT_FALSE(t) << line;
    EXPECT_TRUE(t.error().starts_with(message)) << t.error();
  }
}

TEST(Tokenizer, Utf8AndTabsAreFine) {
  auto t = tokenize("créer\tnœud 'ünïcode ✓' 🤖");
  ASSERT_TRUE(t) << t.error();
  EXPECT_EQ(t->size(), 4u);
  EXPECT_EQ((*t)[3].text, "🤖");
}

TEST(Tokenizer, LineLengthLimit) {
  EXPECT_TRUE(tokenize(std::string(kMaxLineBytes, 'a')));
  auto t = tokenize(std::string(kMaxLineBytes + 1, 'a'));
  ASSERT_FALSE(t);
  EXPECT_EQ(t.error(), "column 4097: line is longer than 4096 bytes");
}

// The shell's line has no nesting: the longest line of the most tokens or quotes is one loop.
TEST(Tokenizer, TheLongestLineOfTokensOrQuotesIsFlat) {
  std::string words;
  while (words.size() + 2 <= kMaxLineBytes) words += "a ";
  auto t = tokenize(words);
  ASSERT_TRUE(t) << t.error();
  EXPECT_EQ(t->size(), kMaxLineBytes / 2);
  std::string quotes;
  while (quotes.size() + 4 <= kMaxLineBytes) quotes += "'(\"";  // each kind of quote holds the other
  t = tokenize(quotes);
  ASSERT_TRUE(t) << t.error();
  EXPECT_EQ(t->size(), 1u);  // joined quotes are one word
  t = tokenize(quotes + "'");
  ASSERT_FALSE(t);
  EXPECT_EQ(t.error(), "column " + std::to_string(quotes.size() + 1) + ": unterminated single quote");
}

TEST(Tokenizer, QuoteWordReadsBack) {
  for (std::string s : {"plain", "", "two words", "a\"b", "back\\slash", "tab\there", "#hash", "it's", "new\nline"}) {
    const std::string q = quote_word(s);
    auto t = tokenize(q);
    ASSERT_TRUE(t) << q << ": " << t.error();
    ASSERT_EQ(t->size(), 1u) << q;
    EXPECT_EQ((*t)[0].text, s) << q;
  }
  EXPECT_EQ(quote_word("plain"), "plain");
}

std::vector<Token> toks(std::string_view line) { return tokenize(line).value(); }

constexpr OptionSpec kSpecs[] = {{"--priority", "N"}, {"--period", "DURATION"}, {"--json", ""}};

TEST(Args, OptionsAndPositionals) {
  const auto t = toks("a --priority 5 b --json --period=30ms \"--not-an-option\" -- --neither");
  auto a = Args::parse(t, kSpecs);
  ASSERT_TRUE(a) << a.error();
  EXPECT_EQ(texts(a->positional()), (std::vector<std::string>{"a", "b", "--not-an-option", "--neither"}));
  EXPECT_TRUE(a->has("--json"));
  auto p = a->integer("--priority", -10, 10);
  ASSERT_TRUE(p);
  EXPECT_EQ(**p, 5);
  auto d = a->duration("--period", 0ms, 1s);
  ASSERT_TRUE(d);
  EXPECT_EQ(**d, 30ms);
  EXPECT_EQ(a->value("--period")->column, 34u);
}

TEST(Args, ErrorsNameTheOption) {
  const std::pair<std::string, std::string> cases[] = {
      {"x --priorty 3", "column 3: unknown option '--priorty' (did you mean '--priority'?)"},
      {"x --priority", "column 3: option '--priority' needs a value (N)"},
      {"--json --json", "column 8: option '--json' given twice"},
      {"--json=1", "column 1: option '--json' takes no value"},
  };
  for (const auto& [line, message] : cases) {
    auto a = Args::parse(toks(line), kSpecs);
    ASSERT_FALSE(a) << line;
    EXPECT_EQ(a.error(), message);
  }
  auto a = Args::parse(toks("--priority abc --period 5parsecs"), kSpecs);
  ASSERT_TRUE(a);
  auto p = a->integer("--priority", -10, 10);
  ASSERT_FALSE(p);
  EXPECT_EQ(p.error(), "column 12: option '--priority': expected an integer, got 'abc'");
  auto d = a->duration("--period", 0ms, 1s);
  ASSERT_FALSE(d);
  EXPECT_EQ(d.error(), "column 25: option '--period': '5parsecs' has no unit: write e.g. 30ms, 1.5s, 250us, 2min");
  auto big = Args::parse(toks("--priority 11"), kSpecs);
  auto q = big->integer("--priority", -10, 10);
  ASSERT_FALSE(q);
  EXPECT_EQ(q.error(), "column 12: option '--priority': value 11 is outside [-10, 10]");
}

TEST(Values, DurationsAndNumbers) {
  EXPECT_EQ(*parse_duration(Token{"0", 1, false}, "period", 0ms, 1s), 0ms);
  EXPECT_EQ(*parse_duration(Token{"1.5s", 1, false}, "period", 0ms, 2s), 1500ms);
  auto over = parse_duration(Token{"3s", 7, false}, "period", 0ms, 2s);
  ASSERT_FALSE(over);
  EXPECT_EQ(over.error(), "column 7: period: 3s is outside [0s, 2s]");
  EXPECT_FALSE(parse_duration(Token{"-5ms", 1, false}, "period", 0ms, 2s));
  EXPECT_FALSE(parse_duration(Token{"10", 1, false}, "period", 0ms, 2s));
  EXPECT_EQ(*parse_real(Token{"-2.5e3", 1, false}, "value"), -2500.0);
  EXPECT_FALSE(parse_real(Token{"nan", 1, false}, "value"));
  EXPECT_FALSE(parse_real(Token{"1e999", 1, false}, "value"));
  EXPECT_FALSE(parse_integer(Token{"12x", 1, false}, "n", 0, 100));
}

TEST(Output, TableIsAlignedAndSplitsAtWhiteSpace) {
  Table t({"NAME", "VALUE", "DOC"});
  t.add({"a", "two words", "free text with spaces"});
  t.add({"longer-name", "", ""});
  const std::string s = t.str();
  EXPECT_EQ(s,
            "NAME         VALUE        DOC\n"
            "a            \"two words\"  free text with spaces\n"
            "longer-name  -            -\n");
}

TEST(Output, JsonIsValidWhateverTheStringsHold) {
  JsonWriter j;
  j.begin_array();
  j.begin_object().field("s", std::string("quote\" back\\ nl\n ctl\x01 bad\xff ok\xc3\xa9")).field("n", 1.5);
  j.field("inf", std::numeric_limits<double>::infinity()).field("i", std::int64_t{-3}).field("b", true).end_object();
  j.begin_object().end_object();
  j.end_array();
  auto parsed = testing::JsonParser::parse(j.str());
  ASSERT_TRUE(parsed) << j.str();
  EXPECT_EQ((*parsed)[0]["s"].string(), "quote\" back\\ nl\n ctl\x01 bad\xef\xbf\xbd ok\xc3\xa9");
  EXPECT_TRUE((*parsed)[0]["inf"].is_null());
  EXPECT_EQ((*parsed)[0]["i"].number(), -3);
}

}  // namespace
}  // namespace symb::shell
