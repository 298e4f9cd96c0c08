// G-code words and their interpretation, after grbl 1.1's gcode.c: the same order of checks and
// the same error numbers where grbl has the feature; a word grbl knows but this machine lacks (a
// spindle, tool changes, stored positions) is error 20 with the word named.
#include "hmc/gcode.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

namespace hmc::grbl {
namespace {

constexpr double kMmPerInch = 25.4;
constexpr double kPi = 3.14159265358979323846;
constexpr double kArcAngularEpsilon = 5e-7;  // grbl's ARC_ANGULAR_TRAVEL_EPSILON
constexpr int kMaxLineNumber = 10000000;     // grbl's MAX_LINE_NUMBER

GrblError fail(int code, std::string message) { return GrblError{code, std::move(message)}; }

std::string hex_byte(unsigned char c) {
  char text[8];
  std::snprintf(text, sizeof text, "0x%02X", c);
  return text;
}

// G and M codes by modal group (grbl's groups; Marlin's M150/M280 are a group of their own).
enum class Group { kNonModal, kMotion, kPlane, kDistance, kArcDistance, kFeedMode, kUnits, kCutter, kToolLength,
                   kCoord, kControl, kStop, kSpindle, kCoolant, kMarlin };

// What a G code (in tenths: G92.1 is 921) is here: its group and whether this machine does it.
struct CodeInfo {
  Group group;
  bool supported;
  const char* why;  // for an unsupported one
};

std::optional<CodeInfo> g_info(int g10) {
  switch (g10) {
    case 0: case 10: case 20: case 30: case 800: return CodeInfo{Group::kMotion, true, ""};
    case 382: case 383: case 384: case 385:
      return CodeInfo{Group::kMotion, false, "probing: the board has no probe input"};
    case 40: return CodeInfo{Group::kNonModal, true, ""};
    case 100: return CodeInfo{Group::kNonModal, true, ""};
    case 280: case 281: case 300: case 301:
      return CodeInfo{Group::kNonModal, false, "stored positions (G28/G30) are not kept by this front end"};
    case 530: case 920: case 921: return CodeInfo{Group::kNonModal, true, ""};
    case 170: return CodeInfo{Group::kPlane, true, ""};
    case 180: case 190: return CodeInfo{Group::kPlane, false, "arcs only in the XY plane (G17)"};
    case 900: case 910: return CodeInfo{Group::kDistance, true, ""};
    case 911: return CodeInfo{Group::kArcDistance, true, ""};
    case 901: return CodeInfo{Group::kArcDistance, false, "arc centres are incremental only (G91.1), as in grbl"};
    case 940: return CodeInfo{Group::kFeedMode, true, ""};
    case 930: return CodeInfo{Group::kFeedMode, false, "inverse time feed (G93)"};
    case 200: case 210: return CodeInfo{Group::kUnits, true, ""};
    case 400: return CodeInfo{Group::kCutter, true, ""};
    case 490: return CodeInfo{Group::kToolLength, true, ""};
    case 431: return CodeInfo{Group::kToolLength, false, "tool length offsets (G43.1)"};
    case 540: case 550: case 560: case 570: case 580: case 590: return CodeInfo{Group::kCoord, true, ""};
    case 610: return CodeInfo{Group::kControl, true, ""};
    default: return std::nullopt;
  }
}

std::optional<CodeInfo> m_info(int m) {
  switch (m) {
    case 0: case 2: case 30: return CodeInfo{Group::kStop, true, ""};
    case 1: return CodeInfo{Group::kStop, false, "optional stop (M1)"};
    case 3: case 4: case 5: return CodeInfo{Group::kSpindle, false, "the board has no spindle"};
    case 7: case 8: case 9: return CodeInfo{Group::kCoolant, false, "the board has no coolant output"};
    case 56: return CodeInfo{Group::kNonModal, false, "parking override (M56)"};
    case 150: case 280: return CodeInfo{Group::kMarlin, true, ""};
    default: return std::nullopt;
  }
}

int axis_index(char letter) { return letter == 'X' ? 0 : letter == 'Y' ? 1 : letter == 'Z' ? 2 : -1; }

bool is_integer(double v) { return std::fabs(v - std::round(v)) < 1e-6; }

}  // namespace

std::string fixed(double value, int decimals) {
  char text[64];
  if (std::fabs(value) < 0.5 * std::pow(10.0, -decimals)) value = 0;  // no "-0.000"
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return text;
}

CleanLine clean_line(std::string_view raw) {
  CleanLine out;
  bool in_parens = false;
  for (size_t i = 0; i < raw.size(); ++i) {
    const auto c = static_cast<unsigned char>(raw[i]);
    if (c >= 0x80 || (c < 0x20 && c != '\t') || c == 0x7F) {
      if (!out.garbage) {
        out.garbage = fail(kExpectedCommandLetter,
                           "byte " + hex_byte(c) + " at column " + std::to_string(i + 1) + " is not G-code");
      }
      continue;
    }
    if (in_parens) {
      if (c == ')') in_parens = false;
      continue;
    }
    if (c == '(') {
      in_parens = true;
    } else if (c == ';') {
      break;
    } else if (c != ' ' && c != '\t') {
      out.text.push_back(static_cast<char>(c >= 'a' && c <= 'z' ? c - 'a' + 'A' : c));
    }
  }
  out.stored = out.text.size();
  return out;
}

GrblResult<std::vector<Word>> split_words(std::string_view s) {
  std::vector<Word> words;
  size_t i = 0;
  while (i < s.size()) {
    const char letter = s[i];
    if (letter < 'A' || letter > 'Z') {
      return fail(kExpectedCommandLetter,
                  std::string("'") + letter + "' at column " + std::to_string(i + 1) + ": expected a word's letter");
    }
    size_t j = i + 1;
    if (j < s.size() && (s[j] == '-' || s[j] == '+')) ++j;
    size_t digits = 0;
    bool point = false;
    while (j < s.size() && ((s[j] >= '0' && s[j] <= '9') || (s[j] == '.' && !point))) {
      if (s[j] == '.') {
        point = true;
      } else {
        ++digits;
      }
      ++j;
    }
    const std::string text(s.substr(i, j - i));
    if (digits == 0) {
      return fail(kBadNumberFormat, "'" + text + "': the letter " + letter + " needs a number after it");
    }
    Word w;
    w.letter = letter;
    w.value = std::strtod(text.c_str() + 1, nullptr);
    w.text = text;
    words.push_back(std::move(w));
    i = j;
  }
  return words;
}

Vec3 Interpreter::work_offset() const {
  Vec3 o{};
  for (size_t a = 0; a < kAxisCount; ++a) o[a] = coord_systems_[static_cast<size_t>(modal_.coord_system)][a] + g92_[a];
  return o;
}

void Interpreter::reset_modal() {
  modal_ = ModalState{};
}

void Interpreter::program_end() {
  // grbl's M2/M30: motion G1, G17, G90, G94, G54, offsets of G92 cleared (its default build).
  modal_.motion = 1;
  modal_.incremental = false;
  modal_.coord_system = 0;
  g92_ = Vec3{};
}

std::string Interpreter::parser_state() const {
  std::string s = "[GC:";
  s += modal_.motion == 80 ? "G80" : "G" + std::to_string(modal_.motion);
  s += " G" + std::to_string(54 + modal_.coord_system);
  s += " G17";
  s += modal_.inches ? " G20" : " G21";
  s += modal_.incremental ? " G91" : " G90";
  s += " G94 M5 M9 T0 F";
  s += modal_.inches ? fixed(modal_.feed / kMmPerInch, 1) : fixed(modal_.feed, 0);
  s += " S0]";
  return s;
}

GrblResult<std::vector<Step>> Interpreter::interpret(std::string_view clean, bool jog) {
  GrblResult<std::vector<Word>> words = split_words(clean);
  if (!words) return words.error();
  if (!jog) return run(*words, false);
  // A jog's G20/G21, G90/G91 and F apply to the jog only (grbl's $J=).
  const ModalState saved = modal_;
  GrblResult<std::vector<Step>> steps = run(*words, true);
  modal_ = saved;
  return steps;
}

GrblResult<std::vector<Step>> Interpreter::run(const std::vector<Word>& words, bool jog) {
  std::map<Group, int> codes;           // group -> code (G in tenths; M as is)
  std::map<Group, std::string> code_text;
  std::map<char, double> values;
  std::map<char, std::string> value_text;
  bool marlin_led = false;

  // Collect the words, checking each on its own (grbl's step 1).
  for (const Word& w : words) {
    if (w.letter == 'G' || w.letter == 'M') {
      std::optional<CodeInfo> info;
      int code = 0;
      if (w.letter == 'G') {
        code = static_cast<int>(std::lround(w.value * 10));
        if (std::fabs(w.value * 10 - code) > 1e-3 ||
            (code % 10 != 0 && !(code == 921 || code == 911 || code == 901 || code == 431 || code / 10 == 38))) {
          return fail(kCommandValueNotInteger, w.text + ": this G-code takes no decimal part");
        }
        info = g_info(code);
        if (!info) return fail(kUnsupportedCommand, w.text + ": not a G-code grbl knows");
      } else {
        if (!is_integer(w.value)) return fail(kCommandValueNotInteger, w.text + ": M-codes are whole numbers");
        code = static_cast<int>(std::lround(w.value));
        info = m_info(code);
        if (!info) return fail(kUnsupportedCommand, w.text + ": not an M-code this front end knows");
        if (code == 150) marlin_led = true;
      }
      if (!info->supported) return fail(kUnsupportedCommand, w.text + ": not supported: " + info->why);
      if (jog && !(info->group == Group::kUnits || info->group == Group::kDistance || code == 530)) {
        return fail(kInvalidJog, w.text + ": a jog ($J=) takes only G20/G21, G90/G91, G53, axis words and F");
      }
      if (codes.count(info->group) != 0) {
        return fail(kModalGroupViolation, w.text + " and " + code_text[info->group] + " are in the same modal group");
      }
      codes[info->group] = code;
      code_text[info->group] = w.text;
      continue;
    }
    if (values.count(w.letter) != 0) return fail(kWordRepeated, w.text + ": the word " + std::string(1, w.letter) + " is given twice");
    values[w.letter] = w.value;
    value_text[w.letter] = w.text;
  }
  const auto has = [&](char l) { return values.count(l) != 0; };
  for (const auto& [letter, value] : values) {
    const std::string& text = value_text[letter];
    switch (letter) {
      case 'X': case 'Y': case 'Z': case 'F': case 'I': case 'J': case 'K': case 'L': case 'N': case 'P': case 'R':
        break;
      case 'S':
        if (codes.count(Group::kMarlin) == 0) return fail(kUnsupportedCommand, text + ": not supported: the board has no spindle");
        break;
      case 'T': return fail(kUnsupportedCommand, text + ": not supported: the board has no tool changer");
      case 'U': case 'B': case 'W':
        if (!marlin_led) return fail(kUnsupportedCommand, text + ": the board has no such axis (only X, Y, Z)");
        break;
      default: return fail(kUnsupportedCommand, text + ": the board has no such word or axis (only X, Y, Z)");
    }
    if (value < 0 && (letter == 'F' || letter == 'N' || letter == 'P' || letter == 'T' || letter == 'S')) {
      return fail(kNegativeValue, text + ": must not be negative");
    }
    if (jog && !(letter == 'X' || letter == 'Y' || letter == 'Z' || letter == 'F' || letter == 'N')) {
      return fail(kInvalidJog, text + ": a jog ($J=) takes only G20/G21, G90/G91, G53, axis words and F");
    }
  }
  if (has('N') && (!is_integer(values['N']) || values['N'] > kMaxLineNumber)) {
    return fail(kInvalidLineNumber, value_text['N'] + ": line numbers are whole numbers up to 10000000");
  }

  std::vector<Step> steps;
  const double scale = ((codes.count(Group::kUnits) != 0 ? codes[Group::kUnits] == 200 : modal_.inches)) ? kMmPerInch : 1.0;
  bool axis_words = has('X') || has('Y') || has('Z');
  const int non_modal = codes.count(Group::kNonModal) != 0 ? codes[Group::kNonModal] : -1;
  const bool motion_given = codes.count(Group::kMotion) != 0;

  // Marlin's servo and LED commands stand alone on their line.
  if (codes.count(Group::kMarlin) != 0) {
    const int m = codes[Group::kMarlin];
    if (codes.size() > 1 || axis_words) {
      return fail(kModalGroupViolation, "M" + std::to_string(m) + " stands alone on its line (no G-code or axis words with it)");
    }
    if (m == 280) {
      if (!has('P') || !has('S')) return fail(kValueWordMissing, "M280 needs P<servo> and S<angle>");
      if (!is_integer(values['P'])) return fail(kCommandValueNotInteger, value_text['P'] + ": servo numbers are whole");
      const double p = values['P'], s = values['S'];
      if (p > 1) return fail(kUnsupportedCommand, value_text['P'] + ": the board has servos P0 and P1 (servo 1 and 2)");
      if (s < 10 || s > 170) return fail(kUnsupportedCommand, value_text['S'] + ": a servo angle is 10 to 170 degrees");
      for (const auto& [letter, v] : values) {
        if (letter != 'P' && letter != 'S' && letter != 'N') return fail(kUnusedWords, value_text[letter] + ": M280 takes P and S only");
      }
      steps.push_back(ServoCommand{static_cast<uint32_t>(p) + 1, static_cast<uint32_t>(std::lround(s))});
    } else {
      const double strip = has('S') ? values['S'] : 0;
      if (!is_integer(strip) || strip > 1) {
        return fail(kUnsupportedCommand, "M150 S" + fixed(strip, 0) + ": the board has strips S0 and S1 (strip 1 and 2)");
      }
      std::array<double, 4> rgbw{};
      const char letters[4] = {'R', 'U', 'B', 'W'};
      for (size_t k = 0; k < 4; ++k) {
        if (!has(letters[k])) continue;
        const double v = values[letters[k]];
        if (v < 0 || v > 255) return fail(kUnsupportedCommand, value_text[letters[k]] + ": a colour is 0 to 255");
        rgbw[k] = v;
      }
      double brightness = 255;
      if (has('P')) {
        brightness = values['P'];
        if (brightness > 255) return fail(kUnsupportedCommand, value_text['P'] + ": brightness is 0 to 255");
      }
      for (const auto& [letter, v] : values) {
        if (std::string("SRUBWPN").find(letter) == std::string::npos) {
          return fail(kUnusedWords, value_text[letter] + ": M150 takes S, R, U, B, W and P only");
        }
      }
      const auto level = [&](double v) { return static_cast<uint32_t>(std::lround(v * brightness / 255.0)); };
      steps.push_back(LedCommand{static_cast<uint32_t>(strip) + 1, level(rgbw[0]), level(rgbw[1]), level(rgbw[2]), level(rgbw[3])});
    }
    return steps;
  }

  // Which command uses the axis words: at most one (error 24).
  const bool axis_non_modal = non_modal == 100 || non_modal == 920;
  int motion = motion_given ? codes[Group::kMotion] : modal_.motion * 10;
  if (motion_given && axis_non_modal && axis_words) {
    return fail(kAxisCommandConflict, code_text[Group::kMotion] + " and " + code_text[Group::kNonModal] + " both use the axis words");
  }
  if (non_modal == 530 && !(motion == 0 || motion == 10)) {
    return fail(kG53InvalidMotionMode, "G53 moves in machine coordinates with G0 or G1 only");
  }
  if (jog) {
    if (!has('F')) return fail(kUndefinedFeedRate, "a jog ($J=) needs its feed rate F");
    if (!axis_words) return fail(kInvalidJog, "a jog ($J=) needs an axis word (X, Y or Z)");
    motion = 10;
  }

  // Modal changes, in grbl's order.
  ModalState next = modal_;
  if (has('F')) next.feed = values['F'] * scale;
  if (codes.count(Group::kUnits) != 0) next.inches = codes[Group::kUnits] == 200;
  if (codes.count(Group::kDistance) != 0) next.incremental = codes[Group::kDistance] == 910;
  if (codes.count(Group::kCoord) != 0) next.coord_system = (codes[Group::kCoord] - 540) / 10;
  if (motion_given) next.motion = codes[Group::kMotion] / 10;

  std::set<char> used;  // value words some command took
  used.insert('N');
  used.insert('F');
  Vec3 offset = coord_systems_[static_cast<size_t>(next.coord_system)];
  std::array<Vec3, 6> systems = coord_systems_;
  Vec3 g92 = g92_;

  if (non_modal == 40) {
    if (!has('P')) return fail(kValueWordMissing, "G4 needs P<seconds>");
    used.insert('P');
    steps.push_back(Dwell{values['P']});
  }
  if (non_modal == 100) {
    if (!has('L') || !has('P')) return fail(kValueWordMissing, "G10 needs L2 or L20 and P<system>");
    if (!is_integer(values['P']) || values['P'] > 6) {
      return fail(kUnsupportedCoordSys, value_text['P'] + ": work coordinate systems are P1 (G54) to P6 (G59), P0 the current one");
    }
    const double l = values['L'];
    if (l != 2 && l != 20) return fail(kUnsupportedCommand, value_text['L'] + ": G10 takes L2 or L20");
    const int p = static_cast<int>(values['P']);
    const size_t index = static_cast<size_t>(p == 0 ? next.coord_system : p - 1);
    for (char letter : {'X', 'Y', 'Z'}) {
      if (!has(letter)) continue;
      const auto a = static_cast<size_t>(axis_index(letter));
      const double v = values[letter] * scale;
      systems[index][a] = l == 2 ? v : position_[a] - g92_[a] - v;
    }
    used.insert('L');
    used.insert('P');
    axis_words = false;
  }
  if (non_modal == 920) {
    for (char letter : {'X', 'Y', 'Z'}) {
      if (!has(letter)) continue;
      const auto a = static_cast<size_t>(axis_index(letter));
      g92[a] = position_[a] - systems[static_cast<size_t>(next.coord_system)][a] - values[letter] * scale;
    }
    axis_words = false;
  }
  if (non_modal == 921) g92 = Vec3{};
  offset = systems[static_cast<size_t>(next.coord_system)];

  // The target of a motion.
  Vec3 target = position_;
  for (char letter : {'X', 'Y', 'Z'}) {
    if (!has(letter)) continue;
    const auto a = static_cast<size_t>(axis_index(letter));
    const double v = values[letter] * scale;
    if (non_modal == 530) {
      target[a] = v;
    } else if (next.incremental) {
      target[a] = position_[a] + v;
    } else {
      target[a] = v + offset[a] + g92[a];
    }
  }
  if (axis_words) {
    if (motion == 800) return fail(kAxisWordsExist, "axis words with G80 (motion cancelled): no command uses them");
    const double feed = jog ? values['F'] * scale : next.feed;
    if (motion == 0) {
      steps.push_back(Move{target, true, 0});
    } else if (motion == 10) {
      if (feed <= 0) return fail(kUndefinedFeedRate, "G1 needs a feed rate: give F");
      steps.push_back(Move{target, false, feed});
    } else {  // G2, G3
      if (feed <= 0) return fail(kUndefinedFeedRate, (motion == 20 ? "G2" : "G3") + std::string(" needs a feed rate: give F"));
      if (!has('X') && !has('Y')) return fail(kNoAxisWordsInPlane, "an arc needs X or Y (the XY plane, G17)");
      if (has('K')) return fail(kUnusedWords, value_text['K'] + ": K is not in the XY plane (G17)");
      const bool clockwise = motion == 20;
      Vec3 centre_offset{};
      const double dx = target[0] - position_[0], dy = target[1] - position_[1];
      if (has('R')) {
        double r = values['R'] * scale;
        used.insert('R');
        if (std::fabs(dx) < 1e-9 && std::fabs(dy) < 1e-9) return fail(kInvalidTarget, "an R arc needs an end point other than its start");
        double h_x2_div_d = 4.0 * r * r - dx * dx - dy * dy;
        if (h_x2_div_d < 0) return fail(kInvalidTarget, "the arc's radius R is too small for the distance to its end");
        h_x2_div_d = -std::sqrt(h_x2_div_d) / std::hypot(dx, dy);
        if (!clockwise) h_x2_div_d = -h_x2_div_d;
        if (r < 0) h_x2_div_d = -h_x2_div_d;
        centre_offset[0] = 0.5 * (dx - dy * h_x2_div_d);
        centre_offset[1] = 0.5 * (dy + dx * h_x2_div_d);
      } else {
        if (!has('I') && !has('J')) return fail(kNoOffsetsInPlane, "an arc needs I and J (its centre) or R");
        used.insert('I');
        used.insert('J');
        centre_offset[0] = has('I') ? values['I'] * scale : 0;
        centre_offset[1] = has('J') ? values['J'] * scale : 0;
        const double r_start = std::hypot(centre_offset[0], centre_offset[1]);
        const double r_end = std::hypot(dx - centre_offset[0], dy - centre_offset[1]);
        const double delta = std::fabs(r_end - r_start);
        if (delta > 0.5 || (delta > 0.005 && delta > 0.001 * r_start)) {
          return fail(kInvalidTarget, "the arc's end is not on its circle (radius " + fixed(r_start, 3) + " at the start, " +
                                          fixed(r_end, 3) + " at the end)");
        }
      }
      for (const Move& segment : arc(position_, target, centre_offset, clockwise, feed)) steps.push_back(segment);
    }
  } else if (motion_given && (motion == 20 || motion == 30)) {
    return fail(kNoAxisWordsInPlane, "an arc needs X or Y (the XY plane, G17)");
  }
  if (codes.count(Group::kStop) != 0) {
    const int m = codes[Group::kStop];
    if (m == 0) {
      steps.push_back(ProgramPause{});
    } else {
      steps.push_back(ProgramEnd{});
    }
  }
  for (const auto& [letter, v] : values) {
    if (axis_index(letter) >= 0 || used.count(letter) != 0) continue;
    return fail(kUnusedWords, value_text[letter] + ": no command on this line uses it");
  }

  // The line is good: its changes apply.
  modal_ = next;
  coord_systems_ = systems;
  g92_ = g92;
  if (axis_words) position_ = target;
  if (codes.count(Group::kStop) != 0 && codes[Group::kStop] != 0) program_end();
  return steps;
}

std::vector<Move> Interpreter::arc(const Vec3& start, const Vec3& end, const Vec3& offset, bool clockwise, double feed) const {
  const double cx = start[0] + offset[0], cy = start[1] + offset[1];
  const double r0x = -offset[0], r0y = -offset[1];
  const double rtx = end[0] - cx, rty = end[1] - cy;
  double travel = std::atan2(r0x * rty - r0y * rtx, r0x * rtx + r0y * rty);
  if (clockwise) {
    if (travel >= -kArcAngularEpsilon) travel -= 2 * kPi;
  } else if (travel <= kArcAngularEpsilon) {
    travel += 2 * kPi;
  }
  const double radius = std::hypot(r0x, r0y);
  const double tol = settings_.arc_tolerance_mm;
  // A chord of angle a strays r(1 - cos(a/2)) from its arc: the largest a within the tolerance.
  const double max_angle = tol < radius ? 2 * std::acos(1 - tol / radius) : kPi;
  const auto segments = static_cast<size_t>(std::max(1.0, std::ceil(std::fabs(travel) / max_angle)));
  const double a0 = std::atan2(r0y, r0x);
  std::vector<Move> moves;
  moves.reserve(segments);
  for (size_t k = 1; k <= segments; ++k) {
    Move m{end, false, feed};
    if (k < segments) {
      const double f = static_cast<double>(k) / static_cast<double>(segments);
      m.target[0] = cx + radius * std::cos(a0 + travel * f);
      m.target[1] = cy + radius * std::sin(a0 + travel * f);
      m.target[2] = start[2] + (end[2] - start[2]) * f;
    }
    moves.push_back(m);
  }
  return moves;
}

}  // namespace hmc::grbl
