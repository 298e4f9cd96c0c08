// Jogging an axis from keys: the keys a terminal sends (arrows, Page Up/Down, their Shift forms,
// + - space z q, Ctrl-C as a byte) decoded into jog actions, the step sizes, and where a jog ends
// once the profile's soft limits have their say. Pure functions, so `hmc jog` keeps only the
// terminal and the session, and the rules are tested without either (jog_test.cpp).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hmc/board_frame.h"
#include "hmc/profile.h"

namespace hmc {

// What one key asks for.
struct JogKey {
  enum class Kind { kMove, kStepUp, kStepDown, kStopAll, kZero, kQuit, kInterrupt };
  Kind kind = Kind::kQuit;
  size_t axis = 0;    // kMove: 0 the first axis (Left/Right), 1 the second (Up/Down), 2 the third (Page Up/Down)
  int dir = 1;        // kMove: +1 (Right, Up, Page Up) or -1
  bool fast = false;  // kMove: Shift held: kJogShiftFactor times the step
  bool operator==(const JogKey& o) const { return kind == o.kind && axis == o.axis && dir == o.dir && fast == o.fast; }
};

inline constexpr double kJogShiftFactor = 10;
// Step sizes, smallest first: an axis of the profile in its units (mm or deg), a bare motor in steps.
inline constexpr std::array<double, 3> kJogProfileSteps{0.1, 1, 10};
inline constexpr std::array<double, 3> kJogMotorSteps{1, 10, 100};
inline constexpr size_t kJogFirstStep = 1;  // the middle size

// The keys a window names instead of spelling them in bytes (hmc-desk), and what each asks for:
// Right/Left the first axis, Up/Down the second, Page Up/Down the third; Shift: fast.
enum class JogArrow : uint8_t { kRight, kLeft, kUp, kDown, kPageUp, kPageDown };
JogKey jog_arrow_key(JogArrow arrow, bool shift);
// A typed character's key: + and = step up, - and _ down, space stop all, z zero, q quit, Ctrl-C.
std::optional<JogKey> jog_char_key(char c);

// The keys in `bytes`, in order. The bytes of a sequence not complete yet stay in `bytes` for the
// next read; other keys and sequences are dropped. Arrows are ESC [ A..D (ESC O A..D in the
// terminal's application mode), Shift+arrow ESC [ 1 ; 2 A (any modifier that includes Shift),
// Page Up/Down ESC [ 5 ~ and ESC [ 6 ~ (ESC [ 5 ; 2 ~ with Shift).
std::vector<JogKey> decode_jog_keys(std::string& bytes);

// Where a jog of `distance` (axis units, signed) from `from` ends: at `from + distance`, or at the
// soft limit it would cross (`at_limit`) where the limits apply (the motor homed or zeroed).
struct JogEnd {
  double target = 0;
  bool at_limit = false;
};
JogEnd jog_end(const Axis& axis, const MotorStatus& motor, double from, double distance);

}  // namespace hmc
