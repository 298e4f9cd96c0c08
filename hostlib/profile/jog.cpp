// Jog keys and jog ends (hmc/jog.h).
#include "hmc/jog.h"

#include <cctype>
#include <cstdlib>

#include "hmc/axis_moves.h"

namespace hmc {

std::vector<JogKey> decode_jog_keys(std::string& bytes) {
  std::vector<JogKey> keys;
  const auto move = [&keys](size_t axis, int dir, bool fast) { keys.push_back({JogKey::Kind::kMove, axis, dir, fast}); };
  size_t i = 0;
  while (i < bytes.size()) {
    const char c = bytes[i];
    if (c != '\x1b') {
      ++i;
      switch (c) {
        case '+': case '=': keys.push_back({JogKey::Kind::kStepUp}); break;
        case '-': case '_': keys.push_back({JogKey::Kind::kStepDown}); break;
        case ' ': keys.push_back({JogKey::Kind::kStopAll}); break;
        case 'z': case 'Z': keys.push_back({JogKey::Kind::kZero}); break;
        case 'q': case 'Q': keys.push_back({JogKey::Kind::kQuit}); break;
        case '\x03': keys.push_back({JogKey::Kind::kInterrupt}); break;  // Ctrl-C with the terminal's signals off
        default: break;
      }
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
      case 'C': move(0, +1, shift); break;
      case 'D': move(0, -1, shift); break;
      case 'A': move(1, +1, shift); break;
      case 'B': move(1, -1, shift); break;
      case '~':
        if (first == "5") move(2, +1, shift);
        if (first == "6") move(2, -1, shift);
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
