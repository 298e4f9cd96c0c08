// Board variant "seed" (the default): the seed's board as far as the evidence goes. The command
// UART and the DRV8711 bus follow from what the seed's firmware uses; the LED strips follow from
// the library it drives them with; every other pin is a guess on a free pin (docs/firmware.md,
// "Pin map", lists the table with its evidence).
//
// Sources: the seed (spec 003, "Serial_port.cpp": commands arrive on "serial5"; LED control
// with Adafruit_NeoPixel_ZeroDMA); Adafruit_NeoPixel_ZeroDMA's pins.h, sercomTable for the
// Arduino Zero and Feather M0 (the only pins it drives: D12 = PA19 on SERCOM1 PAD3 and D5 =
// PA15 on SERCOM2 PAD3, both function C; MOSI = PB10; D6 = PA20 on the Feather only); the
// Zero-derived Arduino variants (Serial5 = SERCOM5 on PB22/PB23, SPI = SERCOM4 on
// PA12/PB10/PB11, function D; the 32.768 kHz crystal on PA00/PA01; native USB on PA24/PA25).
#pragma once

#include "../pin_map.h"

namespace hmc::samd21::boards {

namespace seed_pins {
using namespace pin_map;
constexpr Evidence S = Evidence::kSourced;
constexpr Evidence I = Evidence::kInferred;
constexpr Evidence G = Evidence::kGuessed;

inline constexpr PinAssignment kPins[] = {
    sercom(Role::kUartTx, pb(22), 'D', 5, 2, I, "seed sends commands on Serial5; Zero variants: SERCOM5 PAD2 on PB22"),
    sercom(Role::kUartRx, pb(23), 'D', 5, 3, I, "seed's Serial5; Zero variants: SERCOM5 PAD3 on PB23"),
    sercom(Role::kDriverMiso, pa(12), 'D', 4, 0, I, "seed's Pololu library uses the default SPI: SERCOM4, MISO PA12"),
    sercom(Role::kDriverMosi, pb(10), 'D', 4, 2, I, "default SPI MOSI PB10 (also why no strip is on PB10)"),
    sercom(Role::kDriverSck, pb(11), 'D', 4, 3, I, "default SPI SCK PB11"),
    gpio(Role::kStep1, pa(5), G, "free pin, no source"),
    gpio(Role::kDir1, pa(6), G, "free pin, no source"),
    gpio(Role::kCs1, pa(7), G, "free pin, no source"),
    gpio(Role::kStep2, pa(8), G, "free pin, no source"),
    gpio(Role::kDir2, pa(9), G, "free pin, no source"),
    gpio(Role::kCs2, pa(13), G, "free pin, no source (SERCOM2 PAD1, unrouted: strip 1 needs PAD3 only)"),
    gpio(Role::kStep3, pa(20), G, "free pin, no source"),
    gpio(Role::kDir3, pa(21), G, "free pin, no source"),
    gpio(Role::kCs3, pa(23), G, "free pin, no source"),
    tcc(Role::kServo1, pa(18), 'F', 0, 2, G, "free TCC0 output, no source"),
    tcc(Role::kServo2, pa(22), 'F', 0, 4, G,
        "free TCC0 output (CC0), no source; moved off PA19, which the strip library needs"),
    sercom(Role::kStrip1, pa(15), 'C', 2, 3, I,
           "Adafruit_NeoPixel_ZeroDMA drives only PA19, PA15, PB10 (SPI MOSI), PA20 (Feather, UART SERCOM); "
           "which strip is on which of PA15/PA19 is a guess"),
    sercom(Role::kStrip2, pa(19), 'C', 1, 3, I, "as strip 1: the library's D12, SERCOM1 PAD3"),
    eic(Role::kLimit1Reverse, pb(2), 2, G, "free EXTINT line, no source"),
    eic(Role::kLimit1Forward, pb(3), 3, G, "free EXTINT line, no source"),
    eic(Role::kLimit2Reverse, pb(8), 8, G, "free EXTINT line, no source"),
    eic(Role::kLimit2Forward, pb(9), 9, G, "free EXTINT line, no source"),
    eic(Role::kEmergency, pa(16), 0, G,
        "free EXTINT line, no source; moved off PA15, which the strip library needs"),
    tc(Role::kBuzzer, pa(14), 3, 0, G, "free TC3 output, no source"),
    gpio(Role::kBootLedLeft, pa(27), G, "free pin, no source"),
    gpio(Role::kBootLedRight, pa(28), G, "free pin, no source"),
    gpio(Role::kReserved, pa(0), I, "XIN32: the Zero-derived variants wait for the 32.768 kHz crystal"),
    gpio(Role::kReserved, pa(1), I, "XOUT32: the 32.768 kHz crystal"),
    gpio(Role::kReserved, pa(3), I, "VREFA on the Zero-derived boards (analog reference)"),
    gpio(Role::kReserved, pa(10), S, "the stock bootloader's UART (SERCOM0), HARDWARE.md"),
    gpio(Role::kReserved, pa(11), S, "the stock bootloader's UART (SERCOM0), HARDWARE.md"),
    gpio(Role::kReserved, pa(24), S, "native USB D-: the bootloader's port, HARDWARE.md"),
    gpio(Role::kReserved, pa(25), S, "native USB D+: the bootloader's port, HARDWARE.md"),
    gpio(Role::kReserved, pa(30), S, "SWCLK: the SWD programming port (datasheet)"),
    gpio(Role::kReserved, pa(31), S, "SWDIO: the SWD programming port (datasheet)"),
};
}  // namespace seed_pins

inline constexpr pin_map::BoardVariant kSeed{
    "seed", seed_pins::kPins, sizeof(seed_pins::kPins) / sizeof(seed_pins::kPins[0]), true,
    "the seed's board: UART, DRV8711 bus and LED strips from the evidence, the rest guessed"};

}  // namespace hmc::samd21::boards
