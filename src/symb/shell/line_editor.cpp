#include "symb/shell/line_editor.hpp"

namespace symb::shell {

namespace {

constexpr unsigned char kIac = 255, kSb = 250, kSe = 240, kWill = 251, kDo = 253, kDont = 254, kEcho = 1;
constexpr std::size_t kMaxCsi = 16;      // longer escape sequences are not keys: dropped
constexpr std::size_t kMaxIacSub = 512;  // a subnegotiation longer than this is abandoned

bool continuation(unsigned char c) { return (c & 0xc0u) == 0x80u; }

std::string cursor_left(std::size_t n) { return n == 0 ? std::string() : "\x1b[" + std::to_string(n) + "D"; }
std::string cursor_right(std::size_t n) { return n == 0 ? std::string() : "\x1b[" + std::to_string(n) + "C"; }

}  // namespace

LineEditor::LineEditor(Options options) : options_(std::move(options)) {
  if (options_.max_line == 0) options_.max_line = 1;
}

std::size_t LineEditor::columns(std::size_t from, std::size_t to) const {
  if (secret_) return 0;
  std::size_t n = 0;
  for (std::size_t i = from; i < to && i < line_.size(); ++i)
    if (!continuation(static_cast<unsigned char>(line_[i]))) ++n;
  return n;
}

std::string LineEditor::redraw() const {
  if (!options_.terminal) return {};
  std::string out = "\r" + options_.prompt;
  if (!secret_) out += line_;
  out += "\x1b[K";
  out += cursor_left(columns(cursor_, line_.size()));
  return out;
}

std::string LineEditor::clear_line() const { return options_.terminal ? "\r\x1b[K" : std::string(); }

std::string LineEditor::feed(std::span<const std::byte> bytes, std::vector<EditorEvent>& events) {
  std::string echo;
  for (std::byte b : bytes) {
    const auto c = static_cast<unsigned char>(b);
    // Telnet negotiation (IAC ...) is dropped in both modes; IAC IAC is a literal 0xff.
    switch (state_) {
      case State::kIac:
        if (c == kIac) {
          state_ = State::kNormal;
          break;  // literal 0xff: falls through to the mode below
        }
        if (c == kSb) {
          state_ = State::kIacSub;
          iac_sub_ = 0;
        } else if (c >= kWill && c <= kDont) {
          state_ = State::kIacOption;
          iac_verb_ = c;
        } else {
          state_ = State::kNormal;
        }
        continue;
      case State::kIacOption:
        state_ = State::kNormal;
        if (iac_verb_ == kDo && c == kEcho && !options_.terminal) {
          options_.terminal = true;
          events.push_back({EditorEvent::Kind::kTerminal, {}, echo.size()});
        }
        continue;
      case State::kIacSub:
        if (c == kIac) state_ = State::kIacSubIac;
        if (++iac_sub_ > kMaxIacSub) state_ = State::kNormal;
        continue;
      case State::kIacSubIac: state_ = c == kSe ? State::kNormal : State::kIacSub; continue;
      default:
        if (c == kIac) {
          state_ = State::kIac;
          continue;
        }
    }
    const std::size_t before = events.size();
    if (options_.terminal)
      byte_terminal(c, events, echo);
    else
      byte_plain(c, events);
    for (std::size_t k = before; k < events.size(); ++k) events[k].echo_at = echo.size();
  }
  return echo;
}

void LineEditor::byte_plain(unsigned char c, std::vector<EditorEvent>& events) {
  const bool follows_cr = after_cr_;
  after_cr_ = false;
  if (follows_cr && (c == '\n' || c == 0)) return;
  if (c == '\r' || c == '\n') {
    after_cr_ = c == '\r';
    if (overlong_) {
      overlong_ = false;
      events.push_back(
          {EditorEvent::Kind::kOverlong, "line longer than " + std::to_string(options_.max_line) + " bytes: ignored"});
    } else {
      events.push_back({EditorEvent::Kind::kLine, std::move(line_)});
    }
    line_.clear();
    cursor_ = 0;
    return;
  }
  if (overlong_) return;
  if (line_.size() >= options_.max_line) {
    overlong_ = true;  // the rest up to the line's end is dropped, and the whole line reported
    line_.clear();
    cursor_ = 0;
    return;
  }
  line_.push_back(static_cast<char>(c));
  cursor_ = line_.size();
}

void LineEditor::byte_terminal(unsigned char c, std::vector<EditorEvent>& events, std::string& echo) {
  switch (state_) {
    case State::kEsc:
      if (c == '[') {
        state_ = State::kCsi;
        csi_.clear();
      } else if (c == 'O') {
        state_ = State::kSs3;
      } else {
        state_ = State::kNormal;  // Alt-key or a lone ESC: ignored
      }
      return;
    case State::kCsi:
      if (c < 0x20) {
        state_ = State::kNormal;  // not a sequence after all: the control key counts as typed
        break;
      }
      if (c >= 0x40 && c <= 0x7e) {
        state_ = State::kNormal;
        if (csi_.size() <= kMaxCsi) escape_final(c, echo);
      } else if (csi_.size() <= kMaxCsi) {
        csi_.push_back(static_cast<char>(c));
      }
      return;
    case State::kSs3:
      state_ = State::kNormal;
      csi_.clear();
      escape_final(c, echo);
      return;
    default: break;
  }
  const bool follows_cr = after_cr_;
  after_cr_ = false;
  if (follows_cr && (c == '\n' || c == 0)) return;
  switch (c) {
    case '\r':
    case '\n':
      after_cr_ = c == '\r';
      enter(events, echo);
      return;
    case 0x1b: state_ = State::kEsc; return;
    case 0x7f:
    case 0x08: backspace(echo); return;
    case 0x01: home(echo); return;
    case 0x05: end(echo); return;
    case 0x02: move_left(echo); return;
    case 0x06: move_right(echo); return;
    case 0x03:
      echo += "^C\r\n";
      line_.clear();
      cursor_ = 0;
      history_at_ = history_.size();
      events.push_back({EditorEvent::Kind::kInterrupt, {}});
      return;
    case 0x04:
      if (line_.empty()) {
        events.push_back({EditorEvent::Kind::kEndOfInput, {}});
      } else {
        delete_forward(echo);
      }
      return;
    case 0x15:  // Ctrl-U: erase from the start to the cursor
      line_.erase(0, cursor_);
      cursor_ = 0;
      echo += redraw();
      return;
    case 0x0b:  // Ctrl-K: erase from the cursor to the end
      line_.erase(cursor_);
      echo += "\x1b[K";
      return;
    case 0x0c:  // Ctrl-L: redraw
      echo += "\x1b[2J\x1b[H" + redraw();
      return;
    default: break;
  }
  if (c < 0x20) return;  // other control keys (Tab among them) do nothing here
  insert(c, echo);
}

void LineEditor::escape_final(unsigned char final, std::string& echo) {
  switch (final) {
    case 'A': history_step(-1, echo); return;
    case 'B': history_step(+1, echo); return;
    case 'C': move_right(echo); return;
    case 'D': move_left(echo); return;
    case 'H': home(echo); return;
    case 'F': end(echo); return;
    case '~':
      if (csi_ == "1" || csi_ == "7") home(echo);
      if (csi_ == "4" || csi_ == "8") end(echo);
      if (csi_ == "3") delete_forward(echo);
      return;
    default: return;
  }
}

void LineEditor::enter(std::vector<EditorEvent>& events, std::string& echo) {
  echo += "\r\n";
  std::string line = std::move(line_);
  line_.clear();
  cursor_ = 0;
  if (!secret_ && !line.empty() && (history_.empty() || history_.back() != line)) {
    history_.push_back(line);
    while (history_.size() > options_.history) history_.pop_front();
  }
  history_at_ = history_.size();
  draft_.clear();
  events.push_back({EditorEvent::Kind::kLine, std::move(line)});
}

void LineEditor::insert(unsigned char c, std::string& echo) {
  if (line_.size() >= options_.max_line) {
    echo += '\a';
    return;
  }
  const std::size_t at = cursor_;
  line_.insert(line_.begin() + static_cast<std::ptrdiff_t>(at), static_cast<char>(c));
  ++cursor_;
  if (secret_) return;
  if (at + 1 == line_.size())
    echo.push_back(static_cast<char>(c));  // the terminal puts a character's bytes together itself
  else
    echo += redraw();  // in the middle, a character may be half typed: redraw the whole line
}

void LineEditor::redraw_tail(std::size_t from, std::string& echo) const {
  if (secret_) return;
  // The cursor stands at `from` (a character boundary) on the screen: rewrite the rest of the
  // line, erase what was beyond it, and step back.
  echo += line_.substr(from);
  echo += "\x1b[K";
  echo += cursor_left(columns(cursor_, line_.size()));
}

void LineEditor::backspace(std::string& echo) {
  if (cursor_ == 0) return;
  std::size_t start = cursor_ - 1;
  while (start > 0 && continuation(static_cast<unsigned char>(line_[start]))) --start;
  line_.erase(start, cursor_ - start);
  cursor_ = start;
  if (secret_) return;
  echo += "\b";
  redraw_tail(cursor_, echo);
}

void LineEditor::delete_forward(std::string& echo) {
  if (cursor_ >= line_.size()) return;
  std::size_t end = cursor_ + 1;
  while (end < line_.size() && continuation(static_cast<unsigned char>(line_[end]))) ++end;
  line_.erase(cursor_, end - cursor_);
  redraw_tail(cursor_, echo);
}

void LineEditor::move_left(std::string& echo) {
  if (cursor_ == 0) return;
  --cursor_;
  while (cursor_ > 0 && continuation(static_cast<unsigned char>(line_[cursor_]))) --cursor_;
  if (!secret_) echo += cursor_left(1);
}

void LineEditor::move_right(std::string& echo) {
  if (cursor_ >= line_.size()) return;
  ++cursor_;
  while (cursor_ < line_.size() && continuation(static_cast<unsigned char>(line_[cursor_]))) ++cursor_;
  if (!secret_) echo += cursor_right(1);
}

void LineEditor::home(std::string& echo) {
  echo += cursor_left(columns(0, cursor_));
  cursor_ = 0;
}

void LineEditor::end(std::string& echo) {
  echo += cursor_right(columns(cursor_, line_.size()));
  cursor_ = line_.size();
}

void LineEditor::history_step(int direction, std::string& echo) {
  if (secret_ || history_.empty()) return;
  if (direction < 0) {
    if (history_at_ == 0) return;
    if (history_at_ == history_.size()) draft_ = line_;
    --history_at_;
    replace_line(history_[history_at_], echo);
  } else {
    if (history_at_ >= history_.size()) return;
    ++history_at_;
    replace_line(history_at_ == history_.size() ? draft_ : history_[history_at_], echo);
  }
}

void LineEditor::replace_line(std::string text, std::string& echo) {
  line_ = std::move(text);
  cursor_ = line_.size();
  echo += redraw();
}

}  // namespace symb::shell
