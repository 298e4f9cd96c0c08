// The board's wiring as the port uses it: the pins, peripheral instances, pads and interrupt
// priorities, all derived from the one pin table of the board variant chosen at build time
// (HMC_BOARD, default "seed"; boards/*.h hold the tables with the evidence for every pin,
// pin_map.h the checks they pass). Nothing else in firmware/targets/samd21 names a pin.
#pragma once

#include <stdint.h>

#include "boards/boards.h"
#include "pin_map.h"
#include "regs_port.h"

#ifndef HMC_BOARD
#define HMC_BOARD "seed"
#endif

namespace hmc::samd21::board {

using pin_map::Pin;
using pin_map::Role;

static_assert(boards::has_variant(HMC_BOARD), "HMC_BOARD names no variant in boards/boards.h");
inline constexpr const pin_map::BoardVariant& kVariant = *boards::find_variant(HMC_BOARD);
static_assert(pin_map::check(kVariant).what == nullptr,
              "the board variant's pin table fails its checks: run pin_map_test for the reason");

// The row of a role; every role has one (checked above).
constexpr const pin_map::PinAssignment& row(Role r) { return *pin_map::find(kVariant, r); }
constexpr Pin pin(Role r) { return row(r).pin; }
constexpr port::Function function(Role r) { return static_cast<port::Function>(row(r).function - 'A'); }

inline constexpr uint32_t kCpuHz = 48000000;  // DFLL48M; the step timer counts at this rate

// ---- Clock source --------------------------------------------------------------------------
// True: lock the DFLL48M to a 32.768 kHz crystal on PA00/PA01 (HARDWARE.md's 48 MHz recipe),
// falling back to the factory calibration when no crystal starts within 1.5 s. False: factory
// calibration only (open loop, no reference: less exact, and the UART baud rate, step and servo
// timing are off by as much).
inline constexpr bool kTryCrystal32k = true;

// ---- Command serial line: a SERCOM USART to the FT232RL -----------------------------------
namespace uart {
inline constexpr uint32_t kSercom = row(Role::kUartTx).instance;
inline constexpr Pin kTx = pin(Role::kUartTx);
inline constexpr Pin kRx = pin(Role::kUartRx);
inline constexpr port::Function kTxFunction = function(Role::kUartTx);
inline constexpr port::Function kRxFunction = function(Role::kUartRx);
inline constexpr uint32_t kTxpo = static_cast<uint32_t>(pin_map::usart_txpo(row(Role::kUartTx).index));
inline constexpr uint32_t kRxPad = row(Role::kUartRx).index;
inline constexpr uint32_t kBaud = 115200;
}  // namespace uart

// ---- DRV8711 bus: a SERCOM SPI master, mode 0, MSB first (HARDWARE.md) ---------------------
namespace driver_spi {
inline constexpr uint32_t kSercom = row(Role::kDriverMosi).instance;
inline constexpr Pin kMiso = pin(Role::kDriverMiso);
inline constexpr Pin kMosi = pin(Role::kDriverMosi);
inline constexpr Pin kSck = pin(Role::kDriverSck);
inline constexpr port::Function kMisoFunction = function(Role::kDriverMiso);
inline constexpr port::Function kMosiFunction = function(Role::kDriverMosi);
inline constexpr port::Function kSckFunction = function(Role::kDriverSck);
inline constexpr uint32_t kDopo =
    static_cast<uint32_t>(pin_map::spi_dopo(row(Role::kDriverMosi).index, row(Role::kDriverSck).index));
inline constexpr uint32_t kDiPad = row(Role::kDriverMiso).index;
inline constexpr uint32_t kSckHz = 500000;  // the rate HARDWARE.md cites; the chip allows 4 MHz
}  // namespace driver_spi

// ---- Stepper drivers 1-3: STEP, DIR and chip select (active high) ---------------------------
struct DriverPins {
  Pin step;
  Pin dir;
  Pin cs;
};
inline constexpr DriverPins kDrivers[3] = {
    {pin(Role::kStep1), pin(Role::kDir1), pin(Role::kCs1)},
    {pin(Role::kStep2), pin(Role::kDir2), pin(Role::kCs2)},
    {pin(Role::kStep3), pin(Role::kDir3), pin(Role::kCs3)},
};

// ---- Servos 1 (pan) and 2 (tilt): TCC0 PWM, 50 Hz ------------------------------------------
namespace servo {
inline constexpr Pin kPins[2] = {pin(Role::kServo1), pin(Role::kServo2)};
// WO[n] follows CC[n % 4] (TCC0 has four compare channels; WEXCTRL.OTMX = 0).
inline constexpr uint32_t kChannels[2] = {row(Role::kServo1).index % 4u, row(Role::kServo2).index % 4u};
inline constexpr port::Function kFunctions[2] = {function(Role::kServo1), function(Role::kServo2)};
}  // namespace servo

// ---- SK6812 strips 1-2: one SPI master (data out only) and one DMA channel each -------------
struct LedStripPins {
  Pin data;
  uint32_t sercom;
  port::Function function;
  uint32_t dopo;         // DO on the data pin's pad, the clock pad left unrouted
  uint32_t dma_channel;
};
constexpr LedStripPins strip_pins(Role r, uint32_t dma_channel) {
  return {pin(r), row(r).instance, function(r), static_cast<uint32_t>(pin_map::spi_dopo_data_only(row(r).index)),
          dma_channel};
}
inline constexpr LedStripPins kLedStrips[2] = {strip_pins(Role::kStrip1, 0), strip_pins(Role::kStrip2, 1)};
inline constexpr uint32_t kLedsPerStrip = 90;  // the seed's LED_NUM (HARDWARE.md)
inline constexpr uint32_t kLedBrightness = 100;  // of 255, as the seed sets (HARDWARE.md)

// ---- Switches: EIC lines, function A. Each pin needs its own EXTINT number. ---------------
// Assumed wiring: a switch closes to ground, the pin has the internal pull-up, so pressed reads
// low. Set active_low = false for a switch that opens when pressed (a normally closed limit or
// emergency switch: pressed, or a cut wire, then reads high).
struct SwitchPin {
  Pin pin;
  uint8_t extint;
  bool active_low;
};
// [motor 1-2][end]: end 0 toward reverse (home), end 1 toward forward.
constexpr SwitchPin switch_pin(Role r) { return {pin(r), row(r).index, kVariant.switches_active_low}; }
inline constexpr SwitchPin kLimits[2][2] = {
    {switch_pin(Role::kLimit1Reverse), switch_pin(Role::kLimit1Forward)},
    {switch_pin(Role::kLimit2Reverse), switch_pin(Role::kLimit2Forward)},
};
inline constexpr SwitchPin kEmergency = switch_pin(Role::kEmergency);

// ---- Buzzer: TC3 toggling WO[0] (frequency mode), function E --------------------------------
namespace buzzer {
inline constexpr Pin kPin = pin(Role::kBuzzer);
inline constexpr port::Function kFunction = function(Role::kBuzzer);
}  // namespace buzzer

// ---- Booting LEDs (active high) ------------------------------------------------------------
inline constexpr Pin kBootLedLeft = pin(Role::kBootLedLeft);
inline constexpr Pin kBootLedRight = pin(Role::kBootLedRight);

// ---- Interrupt priorities (0 highest of the M0+'s four) -------------------------------------
// The step timer preempts everything; the UART receiver next (two bytes of hardware buffer,
// 87 µs each at 115200); the switches last, below the step timer as the controller requires.
inline constexpr uint32_t kPriorityStepTimer = 0;
inline constexpr uint32_t kPrioritySerial = 1;
inline constexpr uint32_t kPrioritySwitches = 2;

}  // namespace hmc::samd21::board
