// Table-driven access to typed commands, and their description in words.
//
// Each command type lists its members in wire order once (Layout below); values, construction
// and the checks that the variant matches protocol_facts.h's command table all derive from it.
#include "hmc/command.h"

#include <cstddef>
#include <string>
#include <type_traits>
#include <utility>

namespace hmc {
namespace {

template <typename T>
struct Layout;
template <>
struct Layout<StepperMove> {
  static constexpr std::array kFields{&StepperMove::motor, &StepperMove::dir, &StepperMove::microstep,
                                      &StepperMove::steps, &StepperMove::delay_us};
};
template <>
struct Layout<ServoMove> {
  static constexpr std::array kFields{&ServoMove::servo, &ServoMove::angle};
};
template <>
struct Layout<LedColor> {
  static constexpr std::array kFields{&LedColor::strip, &LedColor::r, &LedColor::g, &LedColor::b, &LedColor::w};
};
template <>
struct Layout<VersionQuery> {
  static constexpr std::array<uint32_t VersionQuery::*, 0> kFields{};
};
template <>
struct Layout<StatusQuery> {
  static constexpr std::array kFields{&StatusQuery::unit};
};
template <>
struct Layout<SetSetting> {
  static constexpr std::array kFields{&SetSetting::motor, &SetSetting::setting, &SetSetting::value};
};
template <>
struct Layout<GetSetting> {
  static constexpr std::array kFields{&GetSetting::motor, &GetSetting::setting};
};
template <>
struct Layout<SoftLimits> {
  static constexpr std::array kFields{&SoftLimits::motor, &SoftLimits::low_sign, &SoftLimits::low,
                                      &SoftLimits::high_sign, &SoftLimits::high};
};
template <>
struct Layout<ChecksumModeCommand> {
  static constexpr std::array kFields{&ChecksumModeCommand::mode};
};
template <>
struct Layout<WatchdogCommand> {
  static constexpr std::array kFields{&WatchdogCommand::timeout_ms};
};
template <>
struct Layout<SetPosition> {
  static constexpr std::array kFields{&SetPosition::motor, &SetPosition::sign, &SetPosition::position};
};

// Alternative I of Command is CommandId I and has that command's number of values.
template <std::size_t... I>
constexpr bool variant_follows_table(std::index_sequence<I...>) {
  return ((proto::kCommands[I].id == static_cast<proto::CommandId>(I) &&
           Layout<std::variant_alternative_t<I, Command>>::kFields.size() == proto::kCommands[I].value_count) &&
          ...);
}
static_assert(std::variant_size_v<Command> == proto::kCommandCount, "one Command alternative per command");
static_assert(variant_follows_table(std::make_index_sequence<std::variant_size_v<Command>>{}),
              "Command's alternatives are ordered by CommandId and hold the table's values");

// Member by member, each a constant of the fold (a loop over the member pointers would leave
// them to run time, and the struct to be written through memory a field at a time).
template <typename T, std::size_t... I>
T from_values(const uint32_t* values, std::index_sequence<I...>) {
  T out{};
  ((out.*(Layout<T>::kFields[I]) = values[I]), ...);
  return out;
}
template <typename T>
T from_values(const uint32_t* values) {
  return from_values<T>(values, std::make_index_sequence<Layout<T>::kFields.size()>{});
}

template <typename T, std::size_t... I>
CommandValues values_of(const T& typed, std::index_sequence<I...>) {
  CommandValues out;
  ((out.values[I] = typed.*(Layout<T>::kFields[I])), ...);
  out.count = sizeof...(I);
  return out;
}

// Makes `out` the alternative `id` names, in place: one comparison per alternative before it
// (the common commands come first) rather than an indirect call.
template <std::size_t... I>
void set_alternative(Command& out, std::size_t id, const uint32_t* values, std::index_sequence<I...>) {
  (void)((id == I && (out.emplace<I>(from_values<std::variant_alternative_t<I, Command>>(values)), true)) || ...);
}

}  // namespace

const proto::CommandSpec& command_spec(const Command& command) {
  return proto::command_spec(command_id(command));
}

CommandValues command_values(const Command& command) {
  return std::visit(
      [](const auto& typed) {
        using T = std::decay_t<decltype(typed)>;
        return values_of(typed, std::make_index_sequence<Layout<T>::kFields.size()>{});
      },
      command);
}

void set_command(Command& out, proto::CommandId id, const uint32_t* values) {
  set_alternative(out, static_cast<std::size_t>(id), values, std::make_index_sequence<std::variant_size_v<Command>>{});
}

Command make_command(proto::CommandId id, const uint32_t* values) {
  Command out;
  set_command(out, id, values);
  return out;
}

const proto::CommandSpec* find_command(std::string_view name) {
  for (const auto& spec : proto::kCommands) {
    if (name == spec.name) return &spec;
  }
  return nullptr;
}

std::string position_text(int64_t position) { return std::to_string(position); }

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

std::string unit_text(uint32_t unit) {
  if (unit >= 1 && unit <= proto::kMotorCount) return "stepper " + std::to_string(unit);
  if (unit == proto::kUnitBoard) return "the board (switches and servos)";
  if (unit == proto::kUnitWatchdog) return "the link watchdog";
  if (unit == proto::kUnitReset) return "the last reset";
  if (unit >= proto::kUnitFirstStrip && unit < proto::kUnitFirstStrip + proto::kStripCount) {
    return "LED strip " + std::to_string(unit - proto::kUnitFirstStrip + 1);
  }
  return "unit " + std::to_string(unit);
}

// "accel (steps/s^2; 0 constant rate)", or "setting 12" for an id outside the table.
std::string setting_text(uint32_t setting) {
  if (setting < 1 || setting > proto::kSettingCount) return "setting " + std::to_string(setting);
  const proto::SettingSpec& s = proto::kSettings[setting - 1];
  return std::string(s.name) + " (" + s.meaning + ")";
}

struct Describer {
  std::string operator()(const StepperMove& s) const { return describe_stepper(s); }
  std::string operator()(const ServoMove& v) const {
    return "servo " + std::to_string(v.servo) + (v.servo == 1 ? " (pan)" : " (tilt)") + " to " +
           std::to_string(v.angle) + " degrees";
  }
  std::string operator()(const LedColor& l) const {
    return "LED strip " + std::to_string(l.strip) + " to R" + std::to_string(l.r) + " G" + std::to_string(l.g) +
           " B" + std::to_string(l.b) + " W" + std::to_string(l.w);
  }
  std::string operator()(const VersionQuery&) const { return "ask for the version and capabilities"; }
  std::string operator()(const StatusQuery& q) const { return "ask for the status of " + unit_text(q.unit); }
  std::string operator()(const SetSetting& s) const {
    return "stepper " + std::to_string(s.motor) + ": set " + setting_text(s.setting) + " to " +
           std::to_string(s.value);
  }
  std::string operator()(const GetSetting& g) const {
    return "stepper " + std::to_string(g.motor) + ": ask for " + setting_text(g.setting);
  }
  std::string operator()(const SoftLimits& l) const {
    std::string who = "stepper " + std::to_string(l.motor);
    if (l.low_position() >= l.high_position()) return who + ": no soft limits";
    return who + ": soft limits " + position_text(l.low_position()) + " to " + position_text(l.high_position()) +
           " (1/256 step)";
  }
  std::string operator()(const ChecksumModeCommand& c) const {
    return c.mode == static_cast<uint32_t>(proto::ChecksumMode::kCrc16) ? "checksums from now on: CRC-16"
                                                                         : "checksums from now on: the seed's sum";
  }
  std::string operator()(const WatchdogCommand& w) const {
    return w.timeout_ms == 0 ? "link watchdog off"
                             : "link watchdog on: brake every motor after " + std::to_string(w.timeout_ms) +
                                   " ms without a line";
  }
  std::string operator()(const SetPosition& p) const {
    return "stepper " + std::to_string(p.motor) + ": its position is " + position_text(p.value()) + " (1/256 step) from now on";
  }
};

}  // namespace

std::string describe(const Command& command) { return std::visit(Describer{}, command); }

Result<LedColor> parse_led_colour(uint32_t strip, std::string_view text) {
  if (text == "off") return LedColor{strip, 0, 0, 0, 0};
  const std::string_view hex = !text.empty() && text[0] == '#' ? text.substr(1) : text;
  if ((hex.size() != 6 && hex.size() != 8) || hex.find_first_not_of("0123456789abcdefABCDEF") != std::string_view::npos) {
    return Error{"colour '" + std::string(text) + "' is not #RRGGBB or #RRGGBBWW (hex), nor R G B W, nor off"};
  }
  const auto byte = [&](size_t i) { return static_cast<uint32_t>(std::stoul(std::string(hex.substr(2 * i, 2)), nullptr, 16)); };
  return LedColor{strip, byte(0), byte(1), byte(2), hex.size() == 8 ? byte(3) : 0};
}

}  // namespace hmc
