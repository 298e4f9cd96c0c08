// Typed commands of the wire protocol (host -> board) and table-driven access to their values.
//
// A Command is one of StepperMove (STM), ServoMove (SVM), LedColor (LED) or, protocol v2,
// VersionQuery (VER), StatusQuery (STA), SetSetting (SET), GetSetting (GET), SoftLimits (LIM)
// and ChecksumModeCommand (CRC). Fields keep the values exactly as received (a stop's unchecked
// fields included), so a decoded frame encodes back to itself. The field order and names are
// protocol_facts.h's; the variant's alternatives are ordered by proto::CommandId.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>

#include "hmc/crc16.h"
#include "hmc/protocol_facts.h"
#include "hmc/result.h"

namespace hmc {

// STM: move, run, stop or home a stepper.
struct StepperMove {
  uint32_t motor = 1;
  uint32_t dir = proto::kActionStop;  // proto::kAction*
  uint32_t microstep = 0;
  uint32_t steps = 0;
  uint32_t delay_us = 0;
  bool operator==(const StepperMove& o) const {
    return motor == o.motor && dir == o.dir && microstep == o.microstep && steps == o.steps &&
           delay_us == o.delay_us;
  }
};

// SVM: turn a servo to an angle.
struct ServoMove {
  uint32_t servo = 1;
  uint32_t angle = 90;
  bool operator==(const ServoMove& o) const { return servo == o.servo && angle == o.angle; }
};

// LED: set a strip to one RGBW colour.
struct LedColor {
  uint32_t strip = 1;
  uint32_t r = 0, g = 0, b = 0, w = 0;
  bool operator==(const LedColor& o) const {
    return strip == o.strip && r == o.r && g == o.g && b == o.b && w == o.w;
  }
};

// VER: ask for the protocol and firmware versions and the board's capabilities. No values.
struct VersionQuery {
  bool operator==(const VersionQuery&) const { return true; }
};

// STA: ask for the status of one unit: 1-3 a motor, proto::kUnitBoard the board (switches,
// servos), from proto::kUnitFirstStrip the LED strips.
struct StatusQuery {
  uint32_t unit = 1;
  bool operator==(const StatusQuery& o) const { return unit == o.unit; }
};

// SET: change a motor setting (proto::kSettings[setting - 1] gives the value's range).
struct SetSetting {
  uint32_t motor = 1;
  uint32_t setting = proto::kSettingCurrent;  // proto::SettingId
  uint32_t value = 0;
  bool operator==(const SetSetting& o) const {
    return motor == o.motor && setting == o.setting && value == o.value;
  }
};

// GET: ask for a motor setting's value (answered by a SET frame).
struct GetSetting {
  uint32_t motor = 1;
  uint32_t setting = proto::kSettingCurrent;
  bool operator==(const GetSetting& o) const { return motor == o.motor && setting == o.setting; }
};

// LIM: soft travel limits in 1/256 step, each a sign (0 plus, 1 minus) and a magnitude.
// low < high enables them; all zero disables them.
struct SoftLimits {
  uint32_t motor = 1;
  uint32_t low_sign = 0, low = 0;
  uint32_t high_sign = 0, high = 0;
  bool operator==(const SoftLimits& o) const {
    return motor == o.motor && low_sign == o.low_sign && low == o.low && high_sign == o.high_sign &&
           high == o.high;
  }
  int64_t low_position() const { return low_sign != 0 ? -int64_t{low} : int64_t{low}; }
  int64_t high_position() const { return high_sign != 0 ? -int64_t{high} : int64_t{high}; }
};

// CRC: the checksum rule from the next line on (proto::ChecksumMode: 0 the seed's sum, 1 CRC-16).
struct ChecksumModeCommand {
  uint32_t mode = 0;
  bool operator==(const ChecksumModeCommand& o) const { return mode == o.mode; }
};

// WDG (protocol 3): arm the link watchdog with a timeout in ms, or disarm it with 0.
struct WatchdogCommand {
  uint32_t timeout_ms = 0;
  bool operator==(const WatchdogCommand& o) const { return timeout_ms == o.timeout_ms; }
};

// POS (protocol 6): a resting motor's position from now on, 1/256 step as a sign and a magnitude
// (zero: all 0). The board reports the motor homed afterwards: its position means something.
struct SetPosition {
  uint32_t motor = 1;
  uint32_t sign = 0, position = 0;
  bool operator==(const SetPosition& o) const { return motor == o.motor && sign == o.sign && position == o.position; }
  int64_t value() const { return sign != 0 ? -int64_t{position} : int64_t{position}; }
};

using Command = std::variant<StepperMove, ServoMove, LedColor, VersionQuery, StatusQuery, SetSetting,
                             GetSetting, SoftLimits, ChecksumModeCommand, WatchdogCommand,
                             SetPosition>;

// A command's values in wire order; only the first `count` are meaningful.
struct CommandValues {
  std::array<uint32_t, proto::kMaxValues> values{};
  uint32_t count = 0;
};

inline proto::CommandId command_id(const Command& command) { return static_cast<proto::CommandId>(command.index()); }
const proto::CommandSpec& command_spec(const Command& command);
CommandValues command_values(const Command& command);
// Builds a command from its values in wire order; `values` holds spec.value_count entries
// (none for VER, so it may then be null).
Command make_command(proto::CommandId id, const uint32_t* values);
// The same, made in `out` in place (no copy for a command read back at once).
void set_command(Command& out, proto::CommandId id, const uint32_t* values);

// The command table entry with this wire name, or nullptr.
const proto::CommandSpec* find_command(std::string_view name);

// One line in words, e.g. "stepper 1 forward 1000 steps at 1/128 step, 500 us per step".
std::string describe(const Command& command);

// A strip's colour as people write it: "#RRGGBB" (white 0), "#RRGGBBWW" (the # optional), or "off".
Result<LedColor> parse_led_colour(uint32_t strip, std::string_view text);

// Signed positions in 1/256 step, as the protocol writes them: "-1600", "0", "409600".
std::string position_text(int64_t position);

}  // namespace hmc
