// LineSplitter: cuts a byte stream that arrives in pieces into protocol lines.
//
// CR and LF each end a line (so LF, CRLF and lone CR all work); blank lines up to the length
// limit are dropped, as the firmware drops them. A line keeps at most proto::kLineMax + 1
// bytes, enough for decode() to refuse it as too long, while `length` counts all of its bytes:
// memory stays bounded whatever arrives.
#pragma once

#include <cstddef>
#include <deque>
#include <optional>
#include <string>
#include <string_view>

namespace hmc {

struct Line {
  std::string text;        // the line's bytes, terminator excluded, cut after kLineMax + 1
  std::size_t length = 0;  // bytes the line really had
  std::size_t number = 0;  // 1-based line number in the stream (CRLF counts once)
};

class LineSplitter {
 public:
  // Takes the next piece of the stream.
  void feed(std::string_view bytes);
  // Ends the stream: a last line without terminator becomes complete.
  void finish();
  // The next complete non-blank line, if any.
  std::optional<Line> next();

 private:
  void end_line();

  std::deque<Line> ready_;
  Line current_;
  std::size_t line_number_ = 1;
  bool after_cr_ = false;
};

}  // namespace hmc
