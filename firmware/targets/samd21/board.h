// The board's wiring: every pin, peripheral instance and interrupt priority the SAMD21 port
// uses, in one file. This is the one place to change for another wiring; nothing else in
// firmware/targets/samd21 names a pin.
//
// What is known of the real board (HARDWARE.md): commands arrive on SERCOM5 (TX PB22, RX PB23,
// function D) through the FT232RL, and the DRV8711 drivers hang on SERCOM4 as an SPI bus (MISO
// PA12, MOSI PB10, SCK PB11, function D) with GPIO chip selects. Everything else below is a
// choice made on free SAMD21G18 pins, keeping these pins free: PA00/PA01 (32 kHz crystal),
// PA10/PA11 (the stock bootloader's UART), PA24/PA25 (native USB, the bootloader's port),
// PA30/PA31 (SWD) and PA03 (analog reference). Pin functions are from the SAMD21 datasheet's
// "I/O Multiplexing" table; docs/firmware.md has this map as a table.
#pragma once

#include <stdint.h>

#include "regs_port.h"

namespace hmc::samd21::board {

// A port pin: group 0 = PA, 1 = PB.
struct Pin {
  uint8_t group;
  uint8_t number;
};
constexpr Pin pa(uint8_t n) { return Pin{0, n}; }
constexpr Pin pb(uint8_t n) { return Pin{1, n}; }

inline constexpr uint32_t kCpuHz = 48000000;  // DFLL48M; the step timer counts at this rate

// ---- Clock source --------------------------------------------------------------------------
// True: lock the DFLL48M to a 32.768 kHz crystal on PA00/PA01 (HARDWARE.md's 48 MHz recipe),
// falling back to the factory calibration when no crystal starts within 1.5 s. False: factory
// calibration only (open loop, no reference: less exact, and the UART baud rate, step and servo
// timing are off by as much).
inline constexpr bool kTryCrystal32k = true;

// ---- Command serial line: SERCOM5 USART to the FT232RL (HARDWARE.md) ------------------------
namespace uart {
inline constexpr uint32_t kSercom = 5;
inline constexpr Pin kTx = pb(22);  // PAD2
inline constexpr Pin kRx = pb(23);  // PAD3
inline constexpr port::Function kFunction = port::Function::kD_SercomAlt;
inline constexpr uint32_t kTxpo = 1;  // TX on PAD2
inline constexpr uint32_t kRxPad = 3;
inline constexpr uint32_t kBaud = 115200;
}  // namespace uart

// ---- DRV8711 bus: SERCOM4 SPI master, mode 0, MSB first (HARDWARE.md) -----------------------
namespace driver_spi {
inline constexpr uint32_t kSercom = 4;
inline constexpr Pin kMiso = pa(12);  // PAD0
inline constexpr Pin kMosi = pb(10);  // PAD2
inline constexpr Pin kSck = pb(11);   // PAD3
inline constexpr port::Function kFunction = port::Function::kD_SercomAlt;
inline constexpr uint32_t kDopo = 1;  // DO PAD2, SCK PAD3
inline constexpr uint32_t kDiPad = 0;
inline constexpr uint32_t kSckHz = 500000;  // the rate HARDWARE.md cites; the chip allows 4 MHz
}  // namespace driver_spi

// ---- Stepper drivers 1-3: STEP, DIR and chip select (active high) ---------------------------
struct DriverPins {
  Pin step;
  Pin dir;
  Pin cs;
};
inline constexpr DriverPins kDrivers[3] = {
    {pa(5), pa(6), pa(7)},
    {pa(8), pa(9), pa(13)},
    {pa(20), pa(21), pa(23)},
};

// ---- Servos 1 (pan) and 2 (tilt): TCC0 PWM, 50 Hz ------------------------------------------
namespace servo {
inline constexpr Pin kPins[2] = {pa(18), pa(19)};   // TCC0 WO[2], WO[3]: function F
inline constexpr uint32_t kChannels[2] = {2, 3};    // WO[n] follows CC[n % 4]
inline constexpr port::Function kFunction = port::Function::kF_Tcc;
}  // namespace servo

// ---- SK6812 strips 1-2: one SPI master (data out only) and one DMA channel each -------------
struct LedStripPins {
  Pin data;
  uint32_t sercom;
  port::Function function;
  uint32_t dopo;         // DO on PAD0 for both
  uint32_t dma_channel;
};
inline constexpr LedStripPins kLedStrips[2] = {
    {pa(16), 1, port::Function::kC_Sercom, 0, 0},  // SERCOM1 PAD0
    {pa(22), 3, port::Function::kC_Sercom, 0, 1},  // SERCOM3 PAD0
};
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
inline constexpr SwitchPin kLimits[2][2] = {
    {{pb(2), 2, true}, {pb(3), 3, true}},
    {{pb(8), 8, true}, {pb(9), 9, true}},
};
inline constexpr SwitchPin kEmergency = {pa(15), 15, true};

// ---- Buzzer: TC3 toggling WO[0] (frequency mode), function E --------------------------------
namespace buzzer {
inline constexpr Pin kPin = pa(14);
inline constexpr port::Function kFunction = port::Function::kE_TcTcc;
}  // namespace buzzer

// ---- Booting LEDs (active high) ------------------------------------------------------------
inline constexpr Pin kBootLedLeft = pa(27);
inline constexpr Pin kBootLedRight = pa(28);

// ---- Interrupt priorities (0 highest of the M0+'s four) -------------------------------------
// The step timer preempts everything; the UART receiver next (two bytes of hardware buffer,
// 87 µs each at 115200); the switches last, below the step timer as the controller requires.
inline constexpr uint32_t kPriorityStepTimer = 0;
inline constexpr uint32_t kPrioritySerial = 1;
inline constexpr uint32_t kPrioritySwitches = 2;

}  // namespace hmc::samd21::board
