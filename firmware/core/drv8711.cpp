// Drv8711: register encoding and the shadow-register driver for the TI DRV8711 (datasheet
// SLVSC40H) on a Pololu 36v4 board, whose documented full-scale current is
// 2.75 V × TORQUE / (256 × ISGAIN × 30 mΩ).
#include "drv8711.h"

namespace hmc::fw::drv8711 {
namespace {

// ---- Current arithmetic -----------------------------------------------------------------
// At gain 40, TORQUE = 256 × 40 × 0.030 Ω × I / 2.75 V = 768 × mA / 6875. The M0+ has no
// divider and gcc -Os turns even a constant division into __aeabi_uidiv, so the quotient is
// found by shift and subtract, exact for every numerator below kDivisor << kQuotientBits.

constexpr uint32_t kTorquePerMilliampNumerator = 768;
constexpr uint32_t kDivisor = 6875;
constexpr uint32_t kQuotientBits = 10;
constexpr uint8_t kHighestGainCode = 3;  // gain 40
constexpr uint32_t kTorqueMax = 255;
static_assert(kMaxCurrentMa * kTorquePerMilliampNumerator < (kDivisor << kQuotientBits),
              "the quotient of the largest request fits kQuotientBits");

// floor(numerator / 6875) for numerator < 6875 << kQuotientBits, without a divide.
constexpr uint32_t divide_by_6875(uint32_t numerator) {
  uint32_t quotient = 0;
  for (uint32_t bit = kQuotientBits; bit-- > 0;) {
    const uint32_t chunk = kDivisor << bit;
    if (numerator >= chunk) {
      numerator -= chunk;
      quotient |= 1u << bit;
    }
  }
  return quotient;
}

// The gain and TORQUE for `milliamps`, which must not exceed kMaxCurrentMa.
constexpr CurrentSetting compute_current_setting(uint32_t milliamps) {
  uint32_t torque_bits = divide_by_6875(kTorquePerMilliampNumerator * milliamps);
  uint8_t gain_code = kHighestGainCode;
  while (torque_bits > kTorqueMax && gain_code > 0) {
    torque_bits >>= 1;
    --gain_code;
  }
  return {gain_code, static_cast<uint8_t>(torque_bits)};
}

// True when `setting` is gain `gain` with TORQUE `torque`.
constexpr bool is_setting(CurrentSetting setting, uint8_t gain, uint8_t torque) {
  return gain_of(setting.gain_code) == gain && setting.torque == torque;
}
// HARDWARE.md's worked values, checked where the compiler can see them.
static_assert(is_setting(compute_current_setting(1000), 40, 111), "1000 mA");
static_assert(is_setting(compute_current_setting(2000), 40, 223), "2000 mA");
static_assert(is_setting(compute_current_setting(3000), 20, 167), "3000 mA");
static_assert(is_setting(compute_current_setting(4000), 20, 223), "4000 mA");

constexpr uint8_t kMaxStepMode = 8;  // 1/256
constexpr uint8_t kLastDecayMode = static_cast<uint8_t>(DecayMode::kAutoMixed);

// A field's value as a byte (every field here is at most 8 bits wide).
constexpr uint8_t byte_of(Field field, uint16_t value) {
  return static_cast<uint8_t>(field.get(value));
}
// A one-bit field's value as a flag.
constexpr bool flag_of(Field field, uint16_t value) { return field.get(value) != 0; }

}  // namespace

// ---- Encode and decode ------------------------------------------------------------------

uint16_t encode(const Ctrl& f) {
  uint16_t value = 0;
  value = ctrl::kEnable.put(value, f.enable);
  value = ctrl::kReverse.put(value, f.reverse);
  value = ctrl::kStep.put(value, f.step);
  value = ctrl::kMode.put(value, f.mode);
  value = ctrl::kExternalStall.put(value, f.external_stall);
  value = ctrl::kGain.put(value, f.gain_code);
  return ctrl::kDeadTime.put(value, f.dead_time_code);
}

uint16_t encode(const Torque& f) {
  return torque::kSampleThreshold.put(torque::kTorque.put(0, f.torque), f.sample_threshold_code);
}

uint16_t encode(const Off& f) {
  return off::kBypassIndexer.put(off::kOffTime.put(0, f.off_time), f.bypass_indexer);
}

uint16_t encode(const Blank& f) {
  return blank::kAdaptiveBlank.put(blank::kBlankTime.put(0, f.blank_time), f.adaptive);
}

uint16_t encode(const Decay& f) {
  return decay::kDecayMode.put(decay::kDecayTime.put(0, f.decay_time),
                               static_cast<uint8_t>(f.mode));
}

uint16_t encode(const Stall& f) {
  uint16_t value = stall::kThreshold.put(0, f.threshold);
  value = stall::kCount.put(value, f.count_code);
  return stall::kDivider.put(value, f.divider_code);
}

uint16_t encode(const Drive& f) {
  uint16_t value = drive::kOcpThreshold.put(0, f.ocp_threshold_code);
  value = drive::kOcpDeglitch.put(value, f.ocp_deglitch_code);
  value = drive::kLowSideTime.put(value, f.low_side_time_code);
  value = drive::kHighSideTime.put(value, f.high_side_time_code);
  value = drive::kLowSideCurrent.put(value, f.low_side_current_code);
  return drive::kHighSideCurrent.put(value, f.high_side_current_code);
}

uint16_t encode(const Faults& f) {
  uint16_t value = status::kOvertemperature.put(0, f.overtemperature);
  value = status::kOvercurrentA.put(value, f.overcurrent_a);
  value = status::kOvercurrentB.put(value, f.overcurrent_b);
  value = status::kPredriverFaultA.put(value, f.predriver_fault_a);
  value = status::kPredriverFaultB.put(value, f.predriver_fault_b);
  value = status::kUndervoltage.put(value, f.undervoltage);
  value = status::kStall.put(value, f.stall);
  return status::kStallLatched.put(value, f.stall_latched);
}

Ctrl decode_ctrl(uint16_t v) {
  return {flag_of(ctrl::kEnable, v),        flag_of(ctrl::kReverse, v),
          flag_of(ctrl::kStep, v),          byte_of(ctrl::kMode, v),
          flag_of(ctrl::kExternalStall, v), byte_of(ctrl::kGain, v),
          byte_of(ctrl::kDeadTime, v)};
}

Torque decode_torque(uint16_t v) {
  return {byte_of(torque::kTorque, v), byte_of(torque::kSampleThreshold, v)};
}

Off decode_off(uint16_t v) { return {byte_of(off::kOffTime, v), flag_of(off::kBypassIndexer, v)}; }

Blank decode_blank(uint16_t v) {
  return {byte_of(blank::kBlankTime, v), flag_of(blank::kAdaptiveBlank, v)};
}

Decay decode_decay(uint16_t v) {
  return {byte_of(decay::kDecayTime, v), static_cast<DecayMode>(byte_of(decay::kDecayMode, v))};
}

Stall decode_stall(uint16_t v) {
  return {byte_of(stall::kThreshold, v), byte_of(stall::kCount, v), byte_of(stall::kDivider, v)};
}

Drive decode_drive(uint16_t v) {
  return {byte_of(drive::kOcpThreshold, v),   byte_of(drive::kOcpDeglitch, v),
          byte_of(drive::kLowSideTime, v),    byte_of(drive::kHighSideTime, v),
          byte_of(drive::kLowSideCurrent, v), byte_of(drive::kHighSideCurrent, v)};
}

Faults decode_status(uint16_t v) {
  return {flag_of(status::kOvertemperature, v), flag_of(status::kOvercurrentA, v),
          flag_of(status::kOvercurrentB, v),    flag_of(status::kPredriverFaultA, v),
          flag_of(status::kPredriverFaultB, v), flag_of(status::kUndervoltage, v),
          flag_of(status::kStall, v),           flag_of(status::kStallLatched, v)};
}

// ---- Step mode and current --------------------------------------------------------------

uint8_t step_mode_for(uint32_t microsteps) {
  for (uint8_t mode = 0; mode <= kMaxStepMode; ++mode) {
    if (microsteps == (1u << mode)) return mode;
  }
  return kNoStepMode;
}

CurrentSetting current_setting_for(uint32_t milliamps) {
  return compute_current_setting(milliamps > kMaxCurrentMa ? kMaxCurrentMa : milliamps);
}

// ---- Drv8711 ----------------------------------------------------------------------------

Drv8711::Drv8711(hal::SpiBus& bus, uint8_t chip) : bus_(bus), chip_(chip) {
  load_reset_values();
}

void Drv8711::reset_settings() {
  load_reset_values();
  apply_settings();
}

void Drv8711::apply_settings() {
  for (uint8_t i = 1; i < kSettingRegisterCount; ++i) write_shadow(static_cast<Register>(i));
  write_shadow(Register::kCtrl);
}

Verification Drv8711::verify_settings() {
  // Filled field by field: gcc -Os would zero a braced 6-byte struct with a memset call.
  Verification result;
  result.status = Status::kOk;
  result.reg = Register::kCtrl;
  result.expected = 0;
  result.actual = 0;
  for (uint8_t i = 0; i < kSettingRegisterCount; ++i) {
    const Register reg = static_cast<Register>(i);
    const uint16_t actual = read_register(reg);
    if (actual != shadow_[i]) {
      result.status = Status::kMismatch;
      result.reg = reg;
      result.expected = shadow_[i];
      result.actual = actual;
      break;
    }
  }
  return result;
}

Status Drv8711::set_step_mode(uint32_t microsteps) {
  const uint8_t mode = step_mode_for(microsteps);
  if (mode == kNoStepMode) return Status::kUnsupportedMicrostep;
  shadow_of(Register::kCtrl) = ctrl::kMode.put(shadow_of(Register::kCtrl), mode);
  write_shadow(Register::kCtrl);
  return Status::kOk;
}

// Two writes change the current. A higher gain lowers the current for the same TORQUE, so
// CTRL goes first when the gain rises and TORQUE first otherwise: the current between the
// writes then never exceeds the larger of the old and new currents.
Status Drv8711::set_current_ma(uint32_t milliamps) {
  const CurrentSetting setting = current_setting_for(milliamps);
  uint16_t& ctrl_shadow = shadow_of(Register::kCtrl);
  const bool gain_rises = setting.gain_code > ctrl::kGain.get(ctrl_shadow);
  ctrl_shadow = ctrl::kGain.put(ctrl_shadow, setting.gain_code);
  shadow_of(Register::kTorque) = torque::kTorque.put(shadow_of(Register::kTorque), setting.torque);
  if (gain_rises) {
    write_shadow(Register::kCtrl);
    write_shadow(Register::kTorque);
  } else {
    write_shadow(Register::kTorque);
    write_shadow(Register::kCtrl);
  }
  return milliamps > kMaxCurrentMa ? Status::kCurrentCapped : Status::kOk;
}

Status Drv8711::set_decay_mode(DecayMode mode) {
  const uint8_t code = static_cast<uint8_t>(mode);
  if (code > kLastDecayMode) return Status::kReservedDecayMode;
  shadow_of(Register::kDecay) = decay::kDecayMode.put(shadow_of(Register::kDecay), code);
  write_shadow(Register::kDecay);
  return Status::kOk;
}

void Drv8711::enable() {
  shadow_of(Register::kCtrl) = ctrl::kEnable.put(shadow_of(Register::kCtrl), 1);
  write_shadow(Register::kCtrl);
}

void Drv8711::disable() {
  shadow_of(Register::kCtrl) = ctrl::kEnable.put(shadow_of(Register::kCtrl), 0);
  write_shadow(Register::kCtrl);
}

void Drv8711::set_direction(bool invert_dir_pin) {
  shadow_of(Register::kCtrl) = ctrl::kReverse.put(shadow_of(Register::kCtrl), invert_dir_pin);
  write_shadow(Register::kCtrl);
}

Faults Drv8711::read_status() { return decode_status(read_register(Register::kStatus)); }

void Drv8711::clear_status() { bus_.transfer16(chip_, write_word(Register::kStatus, 0)); }

uint16_t Drv8711::read_register(Register reg) {
  return static_cast<uint16_t>(bus_.transfer16(chip_, read_word(reg)) & kDataMask);
}

uint16_t Drv8711::shadow(Register reg) const {
  const uint8_t index = static_cast<uint8_t>(reg);
  return index < kSettingRegisterCount ? shadow_[index] : 0;
}

void Drv8711::load_reset_values() {
  for (uint8_t i = 0; i < kSettingRegisterCount; ++i) shadow_[i] = kResetValues[i];
}

void Drv8711::write_shadow(Register reg) {
  bus_.transfer16(chip_, write_word(reg, shadow_of(reg)));
}

}  // namespace hmc::fw::drv8711
