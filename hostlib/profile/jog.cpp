// Jog keys and jog ends (hmc/jog.h).
#include "hmc/jog.h"

#include <cctype>
#include <cstdlib>

#include "hmc/axis_moves.h"

namespace hmc {

JogKey jog_arrow_key(JogArrow arrow, bool shift) {
  const auto move = [shift](size_t axis, int dir) { return JogKey{JogKey::Kind::kMove, axis, dir, shift}; };
  switch (arrow) {
    case JogArrow::kRight: return move(0, +1);
    case JogArrow::kLeft: return move(0, -1);
    case JogArrow::kUp: return move(1, +1);
    case JogArrow::kDown: return move(1, -1);
    case JogArrow::kPageUp: return move(2, +1);
    case JogArrow::kPageDown: return move(2, -1);
  }
  return move(0, +1);
}

std::optional<JogKey> jog_char_key(char c) {
  switch (c) {
    case '+': case '=': return JogKey{JogKey::Kind::kStepUp};
    case '-': case '_': return JogKey{JogKey::Kind::kStepDown};
    case ' ': return JogKey{JogKey::Kind::kStopAll};
    case 'z': case 'Z': return JogKey{JogKey::Kind::kZero};
    case 'q': case 'Q': return JogKey{JogKey::Kind::kQuit};
    case '\x03': return JogKey{JogKey::Kind::kInterrupt};  // Ctrl-C with the terminal's signals off
    default: return std::nullopt;
  }
}

std::vector<JogKey> decode_jog_keys(std::string& bytes) {
  std::vector<JogKey> keys;
  size_t i = 0;
  while (i < bytes.size()) {
    const char c = bytes[i];
    if (c != '\x1b') {
      ++i;
      if (const std::optional<JogKey> key = jog_char_key(c)) keys.push_back(*key);
      continue;
    }
    // ESC: a control sequence's introducer, its parameters (digits and ';'), then its final byte.
    if (i + 1 >= bytes.size()) break;
    if (bytes[i + 1] != '[' && bytes[i + 1] != 'O') {
      ++i;  // the Escape key alone
      continue;
    }
    size_t end = i + 2;
    while (end < bytes.size() && (std::isdigit(static_cast<unsigned char>(bytes[end])) != 0 || bytes[end] == ';')) ++end;
    if (end >= bytes.size()) break;
    const std::string params = bytes.substr(i + 2, end - (i + 2));
    const char final_byte = bytes[end];
    i = end + 1;
    // The modifier parameter is 1 + a bit set: Shift 1, Alt 2, Ctrl 4.
    const size_t semicolon = params.find(';');
    const int modifier = semicolon == std::string::npos ? 1 : std::atoi(params.c_str() + semicolon + 1);
    const bool shift = modifier >= 2 && ((modifier - 1) & 1) != 0;
    const std::string first = params.substr(0, semicolon);
    switch (final_byte) {
      case 'C': keys.push_back(jog_arrow_key(JogArrow::kRight, shift)); break;
      case 'D': keys.push_back(jog_arrow_key(JogArrow::kLeft, shift)); break;
      case 'A': keys.push_back(jog_arrow_key(JogArrow::kUp, shift)); break;
      case 'B': keys.push_back(jog_arrow_key(JogArrow::kDown, shift)); break;
      case '~':
        if (first == "5") keys.push_back(jog_arrow_key(JogArrow::kPageUp, shift));
        if (first == "6") keys.push_back(jog_arrow_key(JogArrow::kPageDown, shift));
        break;
      default: break;
    }
  }
  bytes.erase(0, i);
  return keys;
}

JogEnd jog_end(const Axis& axis, const MotorStatus& motor, double from, double distance) {
  const double target = from + distance;
  if (!beyond_soft_limits(axis, motor, target)) return {target, false};
  return {target > *axis.limit_max ? *axis.limit_max : *axis.limit_min, true};
}

}  // namespace hmc
