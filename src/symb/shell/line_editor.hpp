// LineEditor: turns the raw bytes a shell receives into lines, in one of two modes.
//  - Terminal mode (a person at a terminal in raw mode): the editor echoes, and handles backspace
//    and DEL, left and right arrows, Home and End, Ctrl-A/E (start/end), Ctrl-U (erase to the
//    start), Ctrl-K (erase to the end), Ctrl-C (drop the line), Ctrl-D (end of session on an empty
//    line), up and down through a bounded history. The cursor moves over whole UTF-8 characters.
//    It returns the bytes to send back (echo and redraw, VT100).
//  - Plain mode (a pipe, a script, a TCP client that is not a terminal): no echo, just lines.
// A client tells the editor that a person is typing by sending telnet's IAC DO ECHO (what a
// telnet client in character mode sends, and what `symb shell` sends from a terminal): the editor
// then switches to terminal mode.
// In both, CR, LF, CRLF and CR NUL each end one line, telnet IAC negotiation is dropped, and a line
// never grows past max_line: in terminal mode more input is refused with a bell; in plain mode the
// over-long line is thrown away and reported, so a cut command is never executed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace symb::shell {

struct EditorEvent {
  enum class Kind : std::uint8_t {
    kLine,        // text: a complete line, without its ending
    kOverlong,    // text: an error message; the line was dropped
    kInterrupt,   // Ctrl-C: the line being typed was dropped
    kEndOfInput,  // Ctrl-D on an empty line
    kTerminal     // the client asked for terminal mode (telnet IAC DO ECHO); the editor switched
  };
  Kind kind = Kind::kLine;
  std::string text;
  // How much of feed()'s returned echo came before this event: whoever prints something for the
  // event puts it there, so the screen shows things in the order they happened.
  std::size_t echo_at = 0;
};

class LineEditor {
 public:
  struct Options {
    bool terminal = false;
    std::size_t max_line = 4096;
    std::size_t history = 100;  // lines kept for up/down (terminal mode)
    std::string prompt;         // redrawn in front of the line (terminal mode)
  };
  explicit LineEditor(Options options);

  // Feeds received bytes. Completed lines and other events are appended to `events`; the return
  // value is what to send back to the terminal (empty in plain mode).
  std::string feed(std::span<const std::byte> bytes, std::vector<EditorEvent>& events);
  std::string feed(std::string_view bytes, std::vector<EditorEvent>& events) {
    return feed(std::span<const std::byte>(reinterpret_cast<const std::byte*>(bytes.data()), bytes.size()), events);
  }

  // The prompt and the line being typed, with the cursor in place: what to send after printing
  // something else (a reply, a log line) on a terminal. Empty in plain mode.
  std::string redraw() const;
  // What to send to clear the prompt and line being typed before printing something else.
  std::string clear_line() const;

  void set_prompt(std::string prompt) { options_.prompt = std::move(prompt); }
  const std::string& prompt() const { return options_.prompt; }
  // Echo off: typed characters are not shown (a token); lines are not kept in the history.
  void set_secret(bool secret) { secret_ = secret; }
  bool terminal() const { return options_.terminal; }
  void set_terminal(bool terminal) { options_.terminal = terminal; }

  // The line being typed and the cursor's byte offset in it.
  const std::string& buffer() const { return line_; }
  std::size_t cursor() const { return cursor_; }
  const std::deque<std::string>& history() const { return history_; }

 private:
  enum class State : std::uint8_t { kNormal, kEsc, kCsi, kSs3, kIac, kIacOption, kIacSub, kIacSubIac };

  void byte_terminal(unsigned char c, std::vector<EditorEvent>& events, std::string& echo);
  void byte_plain(unsigned char c, std::vector<EditorEvent>& events);
  void enter(std::vector<EditorEvent>& events, std::string& echo);
  void escape_final(unsigned char final, std::string& echo);
  void insert(unsigned char c, std::string& echo);
  void backspace(std::string& echo);
  void delete_forward(std::string& echo);
  void move_left(std::string& echo);
  void move_right(std::string& echo);
  void home(std::string& echo);
  void end(std::string& echo);
  void history_step(int direction, std::string& echo);
  void replace_line(std::string text, std::string& echo);
  // Rewrites the line from `from` (where the cursor stands on the screen) and puts the cursor back.
  void redraw_tail(std::size_t from, std::string& echo) const;
  std::size_t columns(std::size_t from, std::size_t to) const;

  Options options_;
  std::string line_;
  std::size_t cursor_ = 0;
  bool secret_ = false;
  bool overlong_ = false;  // plain mode: dropping the rest of an over-long line
  bool after_cr_ = false;  // a CR ended the last line: a following LF or NUL is part of it
  State state_ = State::kNormal;
  std::string csi_;             // parameters of an escape sequence being read
  std::size_t iac_sub_ = 0;     // bytes of a telnet subnegotiation skipped so far
  unsigned char iac_verb_ = 0;  // WILL, WONT, DO or DONT of the option being read
  std::deque<std::string> history_;
  std::size_t history_at_ = 0;  // == history_.size(): editing a new line
  std::string draft_;           // the new line, kept while browsing the history
};

}  // namespace symb::shell
