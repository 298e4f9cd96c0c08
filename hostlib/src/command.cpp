// Table-driven access to typed commands, and their description in words.
#include "hmc/command.h"

#include <string>
#include <type_traits>

namespace hmc {

// The variant's alternatives follow CommandId, so an index is an id.
static_assert(std::is_same_v<std::variant_alternative_t<0, Command>, StepperMove> &&
                  static_cast<int>(proto::CommandId::kStepper) == 0 &&
                  std::is_same_v<std::variant_alternative_t<1, Command>, ServoMove> &&
                  static_cast<int>(proto::CommandId::kServo) == 1 &&
                  std::is_same_v<std::variant_alternative_t<2, Command>, LedColor> &&
                  static_cast<int>(proto::CommandId::kLed) == 2,
              "Command's alternatives are ordered by CommandId");

proto::CommandId command_id(const Command& command) {
  return static_cast<proto::CommandId>(command.index());
}

const proto::CommandSpec& command_spec(const Command& command) {
  return proto::command_spec(command_id(command));
}

CommandValues command_values(const Command& command) {
  CommandValues out;
  auto put = [&out](std::initializer_list<uint32_t> values) {
    for (uint32_t v : values) out.values[out.count++] = v;
  };
  if (auto* s = std::get_if<StepperMove>(&command)) {
    put({s->motor, s->dir, s->microstep, s->steps, s->delay_us});
  } else if (auto* v = std::get_if<ServoMove>(&command)) {
    put({v->servo, v->angle});
  } else if (auto* l = std::get_if<LedColor>(&command)) {
    put({l->strip, l->r, l->g, l->b, l->w});
  }
  return out;
}

Command make_command(proto::CommandId id, const uint32_t* v) {
  switch (id) {
    case proto::CommandId::kStepper: return StepperMove{v[0], v[1], v[2], v[3], v[4]};
    case proto::CommandId::kServo: return ServoMove{v[0], v[1]};
    case proto::CommandId::kLed: break;
  }
  return LedColor{v[0], v[1], v[2], v[3], v[4]};
}

const proto::CommandSpec* find_command(std::string_view name) {
  for (const auto& spec : proto::kCommands) {
    if (name == spec.name) return &spec;
  }
  return nullptr;
}

namespace {

std::string step_size(uint32_t microstep) {
  return microstep == 1 ? "full step" : "1/" + std::to_string(microstep) + " step";
}

std::string describe_stepper(const StepperMove& s) {
  std::string who = "stepper " + std::to_string(s.motor);
  switch (s.dir) {
    case proto::kActionStop: return who + " stop";
    case proto::kActionHome: {
      std::string out = who + " home toward its limit switch";
      out += s.microstep == 0 ? ", current microstep" : ", " + step_size(s.microstep);
      out += s.delay_us == 0 ? ", default homing rate" : ", " + std::to_string(s.delay_us) + " us per step";
      if (s.steps != 0) out += ", at most " + std::to_string(s.steps) + " steps";
      return out;
    }
    default: break;
  }
  std::string out = who + (s.dir == proto::kActionForward ? " forward " : " reverse ");
  out += s.steps == 0 ? "until stopped" : std::to_string(s.steps) + (s.steps == 1 ? " step" : " steps");
  out += " at " + step_size(s.microstep) + ", " + std::to_string(s.delay_us) + " us per step";
  return out;
}

}  // namespace

std::string describe(const Command& command) {
  if (auto* s = std::get_if<StepperMove>(&command)) return describe_stepper(*s);
  if (auto* v = std::get_if<ServoMove>(&command)) {
    return std::string("servo ") + std::to_string(v->servo) + (v->servo == 1 ? " (pan)" : " (tilt)") +
           " to " + std::to_string(v->angle) + " degrees";
  }
  const auto& l = std::get<LedColor>(command);
  return "LED strip " + std::to_string(l.strip) + " to R" + std::to_string(l.r) + " G" + std::to_string(l.g) +
         " B" + std::to_string(l.b) + " W" + std::to_string(l.w);
}

}  // namespace hmc
