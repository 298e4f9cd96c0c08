// Drv8711: configures one TI DRV8711 stepper driver (on a Pololu 36v4 board) over SPI.
//
// Sources: TI DRV8711 datasheet (SLVSC40H) for the SPI frame, register map, field layouts and
// reset values; the Pololu High-Power Stepper Motor Driver 36v4's documented current formula
// (30 mΩ sense resistor). /work/shared/HARDWARE.md collects the facts used here.
//
// Two layers:
//   - Pure register encoding: addresses, field layouts, one struct per register with
//     encode()/decode_*(), the 16-bit SPI word, and the microstep and current arithmetic.
//   - The Drv8711 class: one driver bound to a hal::SpiBus and a chip number. It keeps a
//     shadow of every writable register, so changing a field is a read-modify-write of the
//     shadow followed by one SPI write; the chip is read only by read_register(),
//     read_status() and verify_settings().
//
// Stepping: the step interrupt drives the STEP/DIR pins (hal::StepPins); SPI is never used per
// step (RSTEP exists but costs a 16-bit transfer per step on a bus shared by three drivers).
// RDIR (set_direction) inverts the DIR pin inside the chip: it is configuration, set once per
// motor so that "forward" on the DIR pin means forward for how that motor is wired.
//
// Freestanding: no heap, no exceptions, no library beyond <stdint.h>, no run-time division
// (the Cortex-M0+ has no divider). Calls are not for the step interrupt: each SPI transfer
// takes ~32 µs at the 500 kHz bus clock.
#pragma once

#include <stdint.h>

#include "hal.h"

namespace hmc::fw::drv8711 {

// ---- SPI frame --------------------------------------------------------------------------

// Register addresses (bits 14:12 of the SPI word).
enum class Register : uint8_t {
  kCtrl = 0x0,
  kTorque = 0x1,
  kOff = 0x2,
  kBlank = 0x3,
  kDecay = 0x4,
  kStall = 0x5,
  kDrive = 0x6,
  kStatus = 0x7,
};
inline constexpr uint8_t kRegisterCount = 8;
// CTRL..DRIVE: the registers that hold configuration (STATUS holds faults).
inline constexpr uint8_t kSettingRegisterCount = 7;

inline constexpr uint16_t kReadBit = 0x8000;     // bit 15: 1 read, 0 write
inline constexpr uint8_t kAddressShift = 12;     // bits 14:12
inline constexpr uint16_t kDataMask = 0x0FFF;    // bits 11:0

// The SPI word that writes `data` (12 bits; higher bits are dropped) to `reg`.
constexpr uint16_t write_word(Register reg, uint16_t data) {
  return static_cast<uint16_t>((static_cast<uint32_t>(reg) << kAddressShift) | (data & kDataMask));
}

// The SPI word that reads `reg`; the chip returns the data in bits 11:0 of the same transfer.
constexpr uint16_t read_word(Register reg) {
  return static_cast<uint16_t>(kReadBit | (static_cast<uint32_t>(reg) << kAddressShift));
}

// ---- Fields -----------------------------------------------------------------------------

// A bit field of a 12-bit register: `width` bits starting at bit `shift`.
struct Field {
  uint8_t shift;
  uint8_t width;

  // The field's bits in place.
  constexpr uint16_t mask() const {
    return static_cast<uint16_t>(((1u << width) - 1u) << shift);
  }
  // The field's value in `reg`.
  constexpr uint16_t get(uint16_t reg) const {
    return static_cast<uint16_t>((static_cast<uint32_t>(reg) >> shift) & ((1u << width) - 1u));
  }
  // `reg` with the field replaced by `value` (bits of `value` beyond the width are dropped).
  constexpr uint16_t put(uint16_t reg, uint32_t value) const {
    return static_cast<uint16_t>((static_cast<uint32_t>(reg) & ~static_cast<uint32_t>(mask())) |
                                 ((value << shift) & mask()));
  }
};

namespace ctrl {
inline constexpr Field kEnable{0, 1};          // ENBL: 1 = H-bridges on
inline constexpr Field kReverse{1, 1};         // RDIR: 1 = invert the DIR pin
inline constexpr Field kStep{2, 1};            // RSTEP: 1 = one step; self-clearing
inline constexpr Field kMode{3, 4};            // MODE: microsteps = 1 << MODE, 0..8
inline constexpr Field kExternalStall{7, 1};   // EXSTALL: 1 = external stall detect
inline constexpr Field kGain{8, 2};            // ISGAIN: 0..3 = gain 5/10/20/40
inline constexpr Field kDeadTime{10, 2};       // DTIME: 0..3 = 400/450/650/850 ns
}  // namespace ctrl
namespace torque {
inline constexpr Field kTorque{0, 8};           // TORQUE: full-scale current, 0..255
inline constexpr Field kSampleThreshold{8, 3};  // SMPLTH: back-EMF sample threshold
}  // namespace torque
namespace off {
inline constexpr Field kOffTime{0, 8};          // TOFF: fixed off time, 500 ns steps
inline constexpr Field kBypassIndexer{8, 1};    // PWMMODE: 1 = bypass the indexer
}  // namespace off
namespace blank {
inline constexpr Field kBlankTime{0, 8};        // TBLANK: 20 ns steps, 1 µs minimum
inline constexpr Field kAdaptiveBlank{8, 1};    // ABT: 1 = adaptive blanking
}  // namespace blank
namespace decay {
inline constexpr Field kDecayTime{0, 8};        // TDECAY: mixed-decay transition, 500 ns steps
inline constexpr Field kDecayMode{8, 3};        // DECMOD: see DecayMode
}  // namespace decay
namespace stall {
inline constexpr Field kThreshold{0, 8};        // SDTHR: stall threshold
inline constexpr Field kCount{8, 2};            // SDCNT: steps of back-EMF below threshold
inline constexpr Field kDivider{10, 2};         // VDIV: back-EMF divider
}  // namespace stall
namespace drive {
inline constexpr Field kOcpThreshold{0, 2};     // OCPTH
inline constexpr Field kOcpDeglitch{2, 2};      // OCPDEG
inline constexpr Field kLowSideTime{4, 2};      // TDRIVEN
inline constexpr Field kHighSideTime{6, 2};     // TDRIVEP
inline constexpr Field kLowSideCurrent{8, 2};   // IDRIVEN
inline constexpr Field kHighSideCurrent{10, 2}; // IDRIVEP
}  // namespace drive
namespace status {
inline constexpr Field kOvertemperature{0, 1};  // OTS
inline constexpr Field kOvercurrentA{1, 1};     // AOCP (latched)
inline constexpr Field kOvercurrentB{2, 1};     // BOCP (latched)
inline constexpr Field kPredriverFaultA{3, 1};  // APDF (latched)
inline constexpr Field kPredriverFaultB{4, 1};  // BPDF (latched)
inline constexpr Field kUndervoltage{5, 1};     // UVLO
inline constexpr Field kStall{6, 1};            // STD
inline constexpr Field kStallLatched{7, 1};     // STDLAT (latched)
}  // namespace status

// DECMOD values; 6 and 7 are reserved.
enum class DecayMode : uint8_t {
  kSlow = 0,
  kSlowMixed = 1,      // slow decreasing, mixed increasing current
  kFast = 2,
  kMixed = 3,
  kSlowAutoMixed = 4,  // slow decreasing, auto-mixed increasing current
  kAutoMixed = 5,      // the seed firmware's choice
};

// ---- Registers as structs ---------------------------------------------------------------
// Codes are the raw field values; encode() drops bits beyond each field's width.

struct Ctrl {
  bool enable;
  bool reverse;
  bool step;
  uint8_t mode;
  bool external_stall;
  uint8_t gain_code;
  uint8_t dead_time_code;
};
struct Torque {
  uint8_t torque;
  uint8_t sample_threshold_code;
};
struct Off {
  uint8_t off_time;
  bool bypass_indexer;
};
struct Blank {
  uint8_t blank_time;
  bool adaptive;
};
struct Decay {
  uint8_t decay_time;
  DecayMode mode;
};
struct Stall {
  uint8_t threshold;
  uint8_t count_code;
  uint8_t divider_code;
};
struct Drive {
  uint8_t ocp_threshold_code;
  uint8_t ocp_deglitch_code;
  uint8_t low_side_time_code;
  uint8_t high_side_time_code;
  uint8_t low_side_current_code;
  uint8_t high_side_current_code;
};
// STATUS decoded. OTS, OCP, PDF and UVLO switch the H-bridges off; stall is only reported.
struct Faults {
  bool overtemperature;
  bool overcurrent_a;
  bool overcurrent_b;
  bool predriver_fault_a;
  bool predriver_fault_b;
  bool undervoltage;
  bool stall;
  bool stall_latched;

  // True when a fault bit (not a stall bit) is set: the outputs are or were switched off.
  constexpr bool has_fault() const {
    return overtemperature || overcurrent_a || overcurrent_b || predriver_fault_a ||
           predriver_fault_b || undervoltage;
  }
  // True when the stall detector reports, now or since the last clear.
  constexpr bool has_stall() const { return stall || stall_latched; }
};

uint16_t encode(const Ctrl& fields);
uint16_t encode(const Torque& fields);
uint16_t encode(const Off& fields);
uint16_t encode(const Blank& fields);
uint16_t encode(const Decay& fields);
uint16_t encode(const Stall& fields);
uint16_t encode(const Drive& fields);
uint16_t encode(const Faults& fields);
Ctrl decode_ctrl(uint16_t value);
Torque decode_torque(uint16_t value);
Off decode_off(uint16_t value);
Blank decode_blank(uint16_t value);
Decay decode_decay(uint16_t value);
Stall decode_stall(uint16_t value);
Drive decode_drive(uint16_t value);
Faults decode_status(uint16_t value);

// ---- Reset defaults ---------------------------------------------------------------------
// Indexed by Register. CTRL: disabled, 1/4 step, gain 5, dead time 850 ns. TORQUE: 255,
// SMPLTH 1. OFF: 24 µs. BLANK: 2.56 µs. DECAY: slow/mixed, 8 µs. STALL: SDTHR 0x40. DRIVE 0xA59.
inline constexpr uint16_t kResetValues[kSettingRegisterCount] = {
    0xC10, 0x1FF, 0x030, 0x080, 0x110, 0x040, 0xA59};

// ---- Step mode and current --------------------------------------------------------------

inline constexpr uint8_t kNoStepMode = 0xFF;
// The MODE for 1, 2, 4, ..., 256 microsteps per full step; kNoStepMode for any other count.
uint8_t step_mode_for(uint32_t microsteps);

// The 36v4's continuous rating per coil; set_current_ma caps requests here. The chip could be
// told more (gain 5, TORQUE 255 is ~18 A) but the board cannot carry it.
inline constexpr uint32_t kMaxCurrentMa = 4000;

struct CurrentSetting {
  uint8_t gain_code;  // ISGAIN: 3 = gain 40 ... 0 = gain 5
  uint8_t torque;     // TORQUE
};
// ISGAIN and TORQUE for a full-scale current of `milliamps` (capped at kMaxCurrentMa):
// TORQUE = floor(768 × mA / 6875) at gain 40, halved with the gain stepped down while it
// exceeds 255. The result is at most the request and within one TORQUE step of it.
CurrentSetting current_setting_for(uint32_t milliamps);

// ISGAIN code to amplifier gain: 0..3 -> 5, 10, 20, 40.
constexpr uint8_t gain_of(uint8_t gain_code) { return static_cast<uint8_t>(5u << (gain_code & 3u)); }

// ---- The driver -------------------------------------------------------------------------

// What a call did; each method lists the codes it returns.
enum class Status : uint8_t {
  kOk,
  kUnsupportedMicrostep,  // not 1, 2, 4, ..., 256: nothing written
  kCurrentCapped,         // request above kMaxCurrentMa: kMaxCurrentMa applied
  kReservedDecayMode,     // not a DecayMode value: nothing written
  kMismatch,              // a register read back differs from the shadow
};

// The outcome of verify_settings(): on kMismatch, the first register that differed.
struct Verification {
  Status status;       // kOk or kMismatch
  Register reg;        // valid on kMismatch
  uint16_t expected;   // the shadow
  uint16_t actual;     // what the chip returned
};

class Drv8711 {
 public:
  // Binds to `chip` on `bus`. Shadows start at the reset values; nothing is sent.
  Drv8711(hal::SpiBus& bus, uint8_t chip);

  // Sets every shadow to its reset value and writes them (see apply_settings). Leaves the
  // driver disabled. Call 1 ms after power-up.
  void reset_settings();
  // Writes every setting register from its shadow, CTRL last since it holds ENBL.
  void apply_settings();
  // Compares CTRL..DRIVE read back with the shadows. kOk or kMismatch (first differing one).
  Verification verify_settings();

  // Microsteps per full step: 1, 2, 4, ..., 256. kOk or kUnsupportedMicrostep.
  Status set_step_mode(uint32_t microsteps);
  // Full-scale coil current (see current_setting_for). kOk or kCurrentCapped (still applied).
  Status set_current_ma(uint32_t milliamps);
  // kOk or kReservedDecayMode.
  Status set_decay_mode(DecayMode mode);
  // Turns the H-bridges on / off; other CTRL fields keep their values.
  void enable();
  void disable();
  // RDIR: true inverts the DIR pin (for a motor wired the other way round).
  void set_direction(bool invert_dir_pin);

  // Reads and decodes STATUS.
  Faults read_status();
  // Writes 0 to STATUS, clearing the latched bits (a fault still present sets its bit again).
  void clear_status();
  // One register's 12 data bits as the chip returns them.
  uint16_t read_register(Register reg);

  // The value last written (or to be written) to a setting register; STATUS has none (0).
  uint16_t shadow(Register reg) const;
  bool enabled() const { return ctrl::kEnable.get(shadow_[0]) != 0; }

 private:
  // Sets every shadow to its reset value without sending anything.
  void load_reset_values();
  // Sends the shadow of `reg` to the chip.
  void write_shadow(Register reg);
  // The shadow of `reg`, which must be a setting register.
  uint16_t& shadow_of(Register reg) { return shadow_[static_cast<uint8_t>(reg)]; }

  hal::SpiBus& bus_;
  uint8_t chip_;
  uint16_t shadow_[kSettingRegisterCount];
};

}  // namespace hmc::fw::drv8711
