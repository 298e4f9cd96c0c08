// Clock setup for the SAMD21 port: the CPU and GCLK0 at 48 MHz from the DFLL48M, plus the slow
// generators the watchdog and the switch filter use. Run once, first thing in main().
//
// Generators after clocks_init():
//   GCLK0  48 MHz DFLL48M   CPU, step timer, UART, SPI buses, servo PWM, buzzer
//   GCLK1  32.768 kHz XOSC32K, the DFLL's reference (closed loop only)
//   GCLK2  1.024 kHz OSCULP32K / 32   watchdog
//   GCLK3  32.768 kHz OSCULP32K       switch (EIC) input filter
#pragma once

#include <stdint.h>

namespace hmc::samd21 {

enum class ClockSource : uint8_t {
  kCrystalLocked,     // DFLL48M closed loop on the 32.768 kHz crystal (×1465)
  kFactoryCalibrated  // DFLL48M open loop at the factory coarse value (no crystal found)
};

inline constexpr uint32_t kGclkCpu = 0;
inline constexpr uint32_t kGclkDfllRef = 1;
inline constexpr uint32_t kGclkWatchdog = 2;
inline constexpr uint32_t kGclkSlow32k = 3;

ClockSource clocks_init();
// Routes generator `generator` to peripheral channel `id` (gclk::kId*).
void clock_connect(uint32_t id, uint32_t generator);

}  // namespace hmc::samd21
