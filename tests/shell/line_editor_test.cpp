// The line editor: plain mode (lines, CR/LF handling, over-long lines, telnet bytes) and terminal
// mode (echo, editing keys, arrows, history, UTF-8, secret input).
#include "symb/shell/line_editor.hpp"

#include <gtest/gtest.h>

namespace symb::shell {
namespace {

using Kind = EditorEvent::Kind;

struct Fed {
  std::string echo;
  std::vector<EditorEvent> events;
  std::vector<std::string> lines() const {
    std::vector<std::string> out;
    for (const auto& e : events)
      if (e.kind == Kind::kLine) out.push_back(e.text);
    return out;
  }
};

Fed feed(LineEditor& ed, std::string_view bytes) {
  Fed f;
  f.echo = ed.feed(bytes, f.events);
  return f;
}

LineEditor terminal(std::size_t max_line = 4096, std::size_t history = 100) {
  return LineEditor({true, max_line, history, "> "});
}
LineEditor plain(std::size_t max_line = 4096) { return LineEditor({false, max_line, 100, "> "}); }

constexpr std::string_view kUp = "\x1b[A", kDown = "\x1b[B", kRight = "\x1b[C", kLeft = "\x1b[D";

TEST(LineEditorPlain, LinesWithoutEcho) {
  auto ed = plain();
  auto f = feed(ed, "tasks\nhooks --json\r\nlog 5\rtime\r\0");
  EXPECT_EQ(f.lines(), (std::vector<std::string>{"tasks", "hooks --json", "log 5", "time"}));
  EXPECT_TRUE(f.echo.empty());
}

TEST(LineEditorPlain, CrLfSplitAcrossChunksIsOneEnter) {
  auto ed = plain();
  auto a = feed(ed, "one\r");
  auto b = feed(ed, "\ntwo\n\n");
  EXPECT_EQ(a.lines(), (std::vector<std::string>{"one"}));
  EXPECT_EQ(b.lines(), (std::vector<std::string>{"two", ""}));  // LF LF: an empty line
}

TEST(LineEditorPlain, ControlBytesPassThroughForTheTokenizerToRefuse) {
  auto ed = plain();
  auto f = feed(ed, std::string_view("a\x01\x7f\x1b[Ab\n"));
  EXPECT_EQ(f.lines(), (std::vector<std::string>{"a\x01\x7f\x1b[Ab"}));
}

TEST(LineEditorPlain, OverlongLinesAreDroppedAndReported) {
  auto ed = plain(8);
  auto f = feed(ed, "01234567\n0123456789abcdef\nok\n");
  ASSERT_EQ(f.events.size(), 3u);
  EXPECT_EQ(f.events[0].text, "01234567");
  EXPECT_EQ(f.events[1].kind, Kind::kOverlong);
  EXPECT_EQ(f.events[1].text, "line longer than 8 bytes: ignored");
  EXPECT_EQ(f.events[2].text, "ok");
  // Without a line end, memory stays bounded however much comes.
  for (int i = 0; i < 1000; ++i) (void)feed(ed, std::string(1000, 'x'));
  EXPECT_LE(ed.buffer().size(), 8u);
  auto g = feed(ed, "\nafter\n");
  ASSERT_EQ(g.events.size(), 2u);
  EXPECT_EQ(g.events[0].kind, Kind::kOverlong);
  EXPECT_EQ(g.events[1].text, "after");
}

TEST(LineEditorPlain, TelnetNegotiationIsDropped) {
  auto ed = plain();
  // WILL TTYPE, a subnegotiation, NOP, then IAC IAC (a literal 0xff).
  auto f = feed(ed, std::string_view("\xff\xfb\x18"
                                     "ab\xff\xfa\x18\x01\xff\xf0"
                                     "c\xff\xf1"
                                     "d\xff\xff\n"));
  EXPECT_EQ(f.lines(), (std::vector<std::string>{"abcd\xff"}));
}

TEST(LineEditorPlain, DoEchoSwitchesToTerminalMode) {
  auto ed = plain();
  auto f = feed(ed, std::string_view("\xff\xfd\x01"
                                     "ab"));
  ASSERT_EQ(f.events.size(), 1u);
  EXPECT_EQ(f.events[0].kind, Kind::kTerminal);
  EXPECT_TRUE(ed.terminal());
  EXPECT_EQ(f.echo, "ab");
}

TEST(LineEditorTerminal, EchoAndEnter) {
  auto ed = terminal();
  auto f = feed(ed, "tasks\r");
  EXPECT_EQ(f.echo, "tasks\r\n");
  EXPECT_EQ(f.lines(), (std::vector<std::string>{"tasks"}));
  // CR, LF, CRLF and CR NUL: one enter each.
  auto g = feed(ed, std::string_view("a\r\nb\nc\r\0d\r", 10));
  EXPECT_EQ(g.lines(), (std::vector<std::string>{"a", "b", "c", "d"}));
}

TEST(LineEditorTerminal, EventsKnowWhereInTheEchoTheyHappened) {
  auto ed = plain();
  auto f = feed(ed, std::string_view("\xff\xfd\x01"
                                     "ab\rcd\x03"));
  ASSERT_EQ(f.events.size(), 3u);
  EXPECT_EQ(f.events[0].kind, Kind::kTerminal);
  EXPECT_EQ(f.events[0].echo_at, 0u);
  EXPECT_EQ(f.events[1].echo_at, 4u);  // after "ab\r\n"
  EXPECT_EQ(f.events[2].kind, Kind::kInterrupt);
  EXPECT_EQ(f.events[2].echo_at, f.echo.size());
}

TEST(LineEditorTerminal, BackspaceAndDelete) {
  auto ed = terminal();
  auto f = feed(ed,
                "abc\x7f\x7f"
                "d\x08"
                "e\r");
  EXPECT_EQ(f.lines(), (std::vector<std::string>{"ae"}));
  EXPECT_NE(f.echo.find('\b'), std::string::npos);
  auto g = feed(ed, std::string("xyz") + std::string(kLeft) + std::string(kLeft) + "\x1b[3~\r");
  EXPECT_EQ(g.lines(), (std::vector<std::string>{"xz"}));
  auto h = feed(ed, "\x7f\x7fq\r");  // backspace on an empty line does nothing
  EXPECT_EQ(h.lines(), (std::vector<std::string>{"q"}));
}

TEST(LineEditorTerminal, ArrowsInsertInTheMiddle) {
  auto ed = terminal();
  auto f = feed(ed, std::string("hlo") + std::string(kLeft) + std::string(kLeft));
  EXPECT_EQ(ed.cursor(), 1u);
  EXPECT_EQ(f.echo, "hlo\x1b[1D\x1b[1D");
  auto g = feed(ed, "e");
  EXPECT_EQ(ed.buffer(), "helo");
  EXPECT_EQ(ed.cursor(), 2u);
  // The whole line is redrawn with the cursor put back after the 'e'.
  EXPECT_EQ(g.echo, "\r> helo\x1b[K\x1b[2D");
  auto h = feed(ed, std::string(kRight) + std::string(kRight) + std::string(kRight) + "!\r");
  EXPECT_EQ(h.lines(), (std::vector<std::string>{"helo!"}));
}

TEST(LineEditorTerminal, HomeEndAndControlKeys) {
  auto ed = terminal();
  EXPECT_EQ(feed(ed, "world\x01hello \r").lines(), (std::vector<std::string>{"hello world"}));
  EXPECT_EQ(feed(ed, "b\x1b[Ha\x1b[Fc\r").lines(), (std::vector<std::string>{"abc"}));
  EXPECT_EQ(feed(ed, "2\x1b[1~1\x1b[4~3\r").lines(), (std::vector<std::string>{"123"}));
  EXPECT_EQ(feed(ed, "y\x1bOHx\x1bOFz\r").lines(), (std::vector<std::string>{"xyz"}));
  EXPECT_EQ(feed(ed, "junk\x15good\r").lines(), (std::vector<std::string>{"good"}));
  EXPECT_EQ(feed(ed, "keep-cut\x1b[D\x1b[D\x1b[D\x1b[D\x0b\x05!\r").lines(), (std::vector<std::string>{"keep!"}));
  auto c = feed(ed, "half typed\x03");
  ASSERT_EQ(c.events.size(), 1u);
  EXPECT_EQ(c.events[0].kind, Kind::kInterrupt);
  EXPECT_EQ(ed.buffer(), "");
  EXPECT_EQ(c.echo.substr(c.echo.size() - 4), "^C\r\n");
  auto d = feed(ed, "\x04");
  ASSERT_EQ(d.events.size(), 1u);
  EXPECT_EQ(d.events[0].kind, Kind::kEndOfInput);
  // Unknown escape sequences and stray control keys are swallowed.
  EXPECT_EQ(feed(ed, "a\x1b[15~\x1b[1;5Cb\tc\x1b[99999999999999999999999Z\r").lines(),
            (std::vector<std::string>{"abc"}));
}

TEST(LineEditorTerminal, History) {
  auto ed = terminal();
  (void)feed(ed, "one\rtwo\rtwo\r");
  EXPECT_EQ(ed.history().size(), 2u);  // a repeat is kept once
  (void)feed(ed, "dra");
  (void)feed(ed, kUp);
  EXPECT_EQ(ed.buffer(), "two");
  auto up = feed(ed, kUp);
  EXPECT_EQ(ed.buffer(), "one");
  EXPECT_EQ(up.echo, "\r> one\x1b[K");
  (void)feed(ed, kUp);  // at the oldest: stays
  EXPECT_EQ(ed.buffer(), "one");
  (void)feed(ed, kDown);
  EXPECT_EQ(ed.buffer(), "two");
  (void)feed(ed, kDown);
  EXPECT_EQ(ed.buffer(), "dra");  // the line being typed comes back
  (void)feed(ed, "\x15");
  auto again = feed(ed, std::string(kUp) + std::string(kUp) + "\x1bOB" + "!\r");
  EXPECT_EQ(again.lines(), (std::vector<std::string>{"two!"}));
}

TEST(LineEditorTerminal, HistoryIsBounded) {
  auto ed = terminal(4096, 100);
  for (int i = 0; i < 250; ++i) (void)feed(ed, std::to_string(i) + "\r");
  ASSERT_EQ(ed.history().size(), 100u);
  EXPECT_EQ(ed.history().front(), "150");
  EXPECT_EQ(ed.history().back(), "249");
}

TEST(LineEditorTerminal, OverlongInputRingsTheBell) {
  auto ed = terminal(4);
  auto f = feed(ed, "abcdef\r");
  EXPECT_EQ(f.lines(), (std::vector<std::string>{"abcd"}));
  EXPECT_EQ(f.echo, "abcd\a\a\r\n");
}

TEST(LineEditorTerminal, CursorMovesOverWholeUtf8Characters) {
  auto ed = terminal();
  auto f = feed(ed,
                "a\xc3\xa9"
                "b");  // aéb
  EXPECT_EQ(f.echo,
            "a\xc3\xa9"
            "b");
  (void)feed(ed, kLeft);
  (void)feed(ed, kLeft);
  EXPECT_EQ(ed.cursor(), 1u);
  (void)feed(ed, kRight);
  EXPECT_EQ(ed.cursor(), 3u);
  (void)feed(ed, "\x7f");
  EXPECT_EQ(ed.buffer(), "ab");
}

TEST(LineEditorTerminal, SecretInputIsNotEchoedNorKept) {
  auto ed = terminal();
  ed.set_secret(true);
  auto f = feed(ed, "s3cret\r");
  EXPECT_EQ(f.echo, "\r\n");
  EXPECT_EQ(f.lines(), (std::vector<std::string>{"s3cret"}));
  EXPECT_TRUE(ed.history().empty());
}

}  // namespace
}  // namespace symb::shell
