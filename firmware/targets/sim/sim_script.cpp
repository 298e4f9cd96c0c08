// The injected-event language (sim_script.h): parsing commands, times and scripts, applying
// commands to the board, and the status line.
#include "sim_script.h"

#include <algorithm>
#include <limits>
#include <sstream>

namespace hmc::sim {
namespace {

bool is_blank(char c) { return c == ' ' || c == '\t'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  return s;
}

// Takes the first word off `rest`; `rest` keeps what follows the word, blanks included.
std::string_view take_word(std::string_view& rest) {
  size_t start = 0;
  while (start < rest.size() && is_blank(rest[start])) ++start;
  size_t end = start;
  while (end < rest.size() && !is_blank(rest[end])) ++end;
  const std::string_view word = rest.substr(start, end - start);
  rest.remove_prefix(end);
  return word;
}

std::string quoted(std::string_view s) { return "'" + std::string(s) + "'"; }

// A limit switch command's motor and end: `M END` and nothing after.
Result<SimCommand> parse_switch(Action action, std::string_view name, std::string_view rest) {
  const std::string_view motor = take_word(rest);
  const std::string_view end = take_word(rest);
  if (end.empty()) {
    return Result<SimCommand>::fail(
        std::string(name) + " needs a motor and a switch end: " + std::string(name) + " M END");
  }
  if (motor != "1" && motor != "2") {
    return Result<SimCommand>::fail("motor " + quoted(motor) +
                                    ": only motors 1 and 2 have limit switches");
  }
  if (end != "0" && end != "1") {
    return Result<SimCommand>::fail("switch end " + quoted(end) + ": expected 0 or 1");
  }
  if (const std::string_view extra = trim(rest); !extra.empty()) {
    return Result<SimCommand>::fail("unexpected " + quoted(extra) + " after " + std::string(name) +
                                    " " + std::string(motor) + " " + std::string(end));
  }
  SimCommand command;
  command.action = action;
  command.motor = static_cast<uint8_t>(motor[0] - '0');
  command.end = static_cast<uint8_t>(end[0] - '0');
  return Result<SimCommand>::ok(command);
}

bool all_digits(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// Decimal digits as a number; false when it does not fit in 64 bits.
bool to_u64(std::string_view digits, uint64_t& out) {
  uint64_t value = 0;
  for (const char c : digits) {
    const auto digit = static_cast<uint64_t>(c - '0');
    if (value > (std::numeric_limits<uint64_t>::max() - digit) / 10u) return false;
    value = value * 10u + digit;
  }
  out = value;
  return true;
}

const char* json_bool(bool b) { return b ? "true" : "false"; }

}  // namespace

Result<SimCommand> parse_command(std::string_view line) {
  std::string_view rest = line;
  const std::string_view name = take_word(rest);
  if (name.empty()) return Result<SimCommand>::fail("no command");
  if (name == "press") return parse_switch(Action::kPress, name, rest);
  if (name == "release") return parse_switch(Action::kRelease, name, rest);
  if (name == "auto") return parse_switch(Action::kAuto, name, rest);
  SimCommand command;
  if (name == "send") {
    command.action = Action::kSend;
    if (!rest.empty()) command.text = std::string(rest.substr(1));  // after the separating blank
    return Result<SimCommand>::ok(command);
  }
  const std::string_view argument = trim(rest);
  if (name == "estop") {
    if (argument.empty()) {
      command.action = Action::kEstop;
    } else if (argument == "release") {
      command.action = Action::kEstopRelease;
    } else {
      return Result<SimCommand>::fail("estop takes nothing or 'release', got " + quoted(argument));
    }
    return Result<SimCommand>::ok(command);
  }
  if (name == "fault") {
    std::string_view words = argument;
    const std::string_view motor = take_word(words);
    const std::string_view bits = take_word(words);
    uint64_t m = 0, b = 0;
    if (!all_digits(motor) || !to_u64(motor, m) || m < 1 || m > 3) {
      return Result<SimCommand>::fail("fault: motor " + quoted(motor) + " is not 1, 2 or 3");
    }
    if (!all_digits(bits) || !to_u64(bits, b) || b > 255 || !trim(words).empty()) {
      return Result<SimCommand>::fail("fault: expected STATUS bits 0-255 after the motor, got " + quoted(argument));
    }
    command.action = Action::kFault;
    command.motor = static_cast<uint8_t>(m);
    command.end = static_cast<uint8_t>(b);
    return Result<SimCommand>::ok(command);
  }
  if (name == "status") {
    if (!argument.empty()) return Result<SimCommand>::fail("status takes no arguments");
    command.action = Action::kStatus;
    return Result<SimCommand>::ok(command);
  }
  return Result<SimCommand>::fail("unknown command " + quoted(name) +
                                  " (expected press, release, auto, estop, fault, send or status)");
}

Result<Ticks> parse_time(std::string_view text) {
  struct Unit {
    std::string_view suffix;
    uint64_t ticks;
  };
  // Two-letter suffixes first: "ms" also ends in "s".
  static constexpr Unit kUnits[] = {{"ms", hal::kTicksPerSecond / 1000u},
                                    {"us", hal::kTicksPerMicrosecond},
                                    {"s", hal::kTicksPerSecond},
                                    {"t", 1}};
  const Unit* unit = nullptr;
  for (const Unit& candidate : kUnits) {
    const std::string_view s = candidate.suffix;
    if (text.size() > s.size() && text.substr(text.size() - s.size()) == s) {
      unit = &candidate;
      break;
    }
  }
  if (unit == nullptr) {
    return Result<Ticks>::fail("time " + quoted(text) +
                               ": expected a number and a unit s, ms, us or t (ticks)");
  }
  const std::string_view number = text.substr(0, text.size() - unit->suffix.size());
  const size_t dot = number.find('.');
  const std::string_view whole = number.substr(0, dot);
  const std::string_view fraction =
      dot == std::string_view::npos ? std::string_view{} : number.substr(dot + 1);
  const bool has_dot = dot != std::string_view::npos;
  if (!all_digits(whole) || (has_dot && !all_digits(fraction))) {
    return Result<Ticks>::fail("time " + quoted(text) + ": " + quoted(number) +
                               " is not a decimal number");
  }
  if (has_dot && unit->ticks == 1) {
    return Result<Ticks>::fail("time " + quoted(text) + ": ticks are whole numbers");
  }
  constexpr size_t kMaxFractionDigits = 9;
  if (fraction.size() > kMaxFractionDigits) {
    return Result<Ticks>::fail("time " + quoted(text) + ": at most 9 digits after the point");
  }
  uint64_t whole_value = 0;
  uint64_t fraction_value = 0;
  const bool fits = to_u64(whole, whole_value) && to_u64(fraction, fraction_value);
  uint64_t scale = 1;
  for (size_t i = 0; i < fraction.size(); ++i) scale *= 10u;
  // fraction_value < 10^9 and unit->ticks <= 48e6: the product fits in 64 bits.
  const uint64_t fraction_ticks = fraction_value * unit->ticks;
  if (fraction_ticks % scale != 0) {
    return Result<Ticks>::fail("time " + quoted(text) +
                               " is not a whole number of ticks (48 per us)");
  }
  const uint64_t limit = (kNever - 1u - fraction_ticks / scale) / unit->ticks;
  if (!fits || whole_value > limit) {
    return Result<Ticks>::fail("time " + quoted(text) + " is too large");
  }
  return Result<Ticks>::ok(whole_value * unit->ticks + fraction_ticks / scale);
}

Result<std::vector<ScriptEvent>> parse_script(std::string_view text) {
  using ScriptResult = Result<std::vector<ScriptEvent>>;
  std::vector<ScriptEvent> events;
  uint32_t line_number = 0;
  while (!text.empty()) {
    const size_t end = text.find('\n');
    std::string_view line = text.substr(0, end);
    text.remove_prefix(end == std::string_view::npos ? text.size() : end + 1);
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    const std::string_view content = trim(line);
    if (content.empty() || content.front() == '#') continue;

    const std::string prefix = std::to_string(line_number) + ": ";
    std::string_view rest = line;
    if (take_word(rest) != "at") return ScriptResult::fail(prefix + "expected 'at TIME COMMAND'");
    const std::string_view time_word = take_word(rest);
    if (time_word.empty()) return ScriptResult::fail(prefix + "expected a time after 'at'");
    Result<Ticks> at = parse_time(time_word);
    if (!at) return ScriptResult::fail(prefix + at.error);
    if (trim(rest).empty()) return ScriptResult::fail(prefix + "expected a command after the time");
    Result<SimCommand> command = parse_command(rest);
    if (!command) return ScriptResult::fail(prefix + command.error);
    if (command.value->action == Action::kStatus) {
      return ScriptResult::fail(prefix + "status is for the control channel only");
    }
    events.push_back(ScriptEvent{*at.value, std::move(*command.value), line_number});
  }
  std::stable_sort(events.begin(), events.end(),
                   [](const ScriptEvent& a, const ScriptEvent& b) { return a.at < b.at; });
  return ScriptResult::ok(std::move(events));
}

void apply_command(SimBoard& board, const SimCommand& command) {
  switch (command.action) {
    case Action::kPress:
      board.force_limit(command.motor, command.end, Force::kPressed);
      break;
    case Action::kRelease:
      board.force_limit(command.motor, command.end, Force::kReleased);
      break;
    case Action::kAuto:
      board.force_limit(command.motor, command.end, Force::kNone);
      break;
    case Action::kEstop:
      board.set_emergency(true);
      break;
    case Action::kEstopRelease:
      board.set_emergency(false);
      break;
    case Action::kFault:
      board.set_driver_fault(command.motor, command.end);
      break;
    case Action::kSend:
      board.send(command.text + "\n");
      break;
    case Action::kStatus:
      break;  // an answer, not an action: status_json()
  }
}

std::string status_json(const SimBoard& board) {
  std::ostringstream out;
  out << "{\"t\":" << board.now() << ",\"emergency\":" << json_bool(board.emergency_pressed())
      << ",\"motors\":[";
  const fw::Controller& controller = board.controller();
  for (uint8_t motor = 1; motor <= proto::kMotorCount; ++motor) {
    if (motor > 1) out << ',';
    out << "{\"motor\":" << int{motor} << ",\"pos\":" << board.axis_position(motor)
        << ",\"fw_pos\":" << controller.position(motor) << ",\"steps\":" << board.steps(motor)
        << ",\"state\":\"" << state_name(controller.state(motor)) << '"'
        << ",\"homed\":" << json_bool(controller.homed(motor)) << ",\"switches\":";
    if (proto::motor_has_switches(motor)) {
      out << '[' << json_bool(board.limit_pressed(motor, 0)) << ','
          << json_bool(board.limit_pressed(motor, 1)) << ']';
    } else {
      out << "null";
    }
    out << ",\"microstep\":" << board.driver_microstep(motor)
        << ",\"enabled\":" << json_bool(board.driver_enabled(motor)) << '}';
  }
  out << "],\"servos\":[";
  for (uint8_t servo = 1; servo <= proto::kServoCount; ++servo) {
    if (servo > 1) out << ',';
    out << "{\"servo\":" << int{servo} << ",\"pulse_us\":" << board.servo_pulse(servo) << '}';
  }
  out << "],\"leds\":[";
  for (uint8_t strip = 1; strip <= proto::kStripCount; ++strip) {
    if (strip > 1) out << ',';
    const std::array<uint8_t, 4> c = board.led(strip);
    out << "{\"strip\":" << int{strip} << ",\"r\":" << int{c[0]} << ",\"g\":" << int{c[1]}
        << ",\"b\":" << int{c[2]} << ",\"w\":" << int{c[3]} << '}';
  }
  out << "]}";
  return out.str();
}

}  // namespace hmc::sim
