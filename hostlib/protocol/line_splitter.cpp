// Cuts a byte stream into protocol lines (docs/protocol.md "Lines").
#include "hmc/line_splitter.h"

#include "hmc/codec.h"

namespace hmc {

void LineSplitter::feed(std::string_view bytes) {
  for (char c : bytes) {
    if (c == '\n' && after_cr_) {  // the LF of a CRLF: the line already ended at the CR
      after_cr_ = false;
      continue;
    }
    after_cr_ = c == '\r';
    if (c == '\r' || c == '\n') {
      end_line();
      continue;
    }
    if (current_.text.size() <= proto::kLineMax) current_.text += c;
    ++current_.length;
  }
}

void LineSplitter::finish() {
  if (current_.length > 0) end_line();
  after_cr_ = false;
}

std::optional<Line> LineSplitter::next() {
  if (ready_.empty()) return std::nullopt;
  Line line = std::move(ready_.front());
  ready_.pop_front();
  return line;
}

void LineSplitter::end_line() {
  current_.number = line_number_++;
  // Length is judged before blankness: an over-long blank line is still refused.
  if (current_.length > proto::kLineMax || !is_blank(current_.text)) ready_.push_back(std::move(current_));
  current_ = Line{};
}

}  // namespace hmc
