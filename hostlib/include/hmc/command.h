// Typed commands of the wire protocol and table-driven access to their values.
//
// A Command is one of StepperMove (STM), ServoMove (SVM) or LedColor (LED). Fields keep the
// values exactly as received (a stop's unchecked fields included), so a decoded frame encodes
// back to itself. The field order and names are protocol_facts.h's.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <variant>

#include "core/protocol_facts.h"

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

using Command = std::variant<StepperMove, ServoMove, LedColor>;

// A command's values in wire order; only the first `count` are meaningful.
struct CommandValues {
  std::array<uint32_t, proto::kMaxValues> values{};
  uint32_t count = 0;
};

proto::CommandId command_id(const Command& command);
const proto::CommandSpec& command_spec(const Command& command);
CommandValues command_values(const Command& command);
// Builds a command from its values in wire order; `values` holds spec.value_count entries.
Command make_command(proto::CommandId id, const uint32_t* values);

// The command table entry with this wire name, or nullptr.
const proto::CommandSpec* find_command(std::string_view name);

// One line in words, e.g. "stepper 1 forward 1000 steps at 1/128 step, 500 us per step".
std::string describe(const Command& command);

}  // namespace hmc
