// Board variant "bench": the pin map this port used before the LED strip evidence was found
// (docs/firmware.md before board variants), kept for benches wired to that table. Only the UART and
// the DRV8711 bus agree with the seed's board; the strips are on pins the seed's LED library
// cannot drive, so on the seed's board this variant drives the emergency switch and tilt servo
// pins against the strips' data lines. Build with -DHMC_BOARD=bench.
#pragma once

#include "../pin_map.h"

namespace hmc::samd21::boards {

namespace bench_pins {
using namespace pin_map;
constexpr Evidence S = Evidence::kSourced;
constexpr Evidence I = Evidence::kInferred;
constexpr Evidence G = Evidence::kGuessed;

inline constexpr PinAssignment kPins[] = {
    sercom(Role::kUartTx, pb(22), 'D', 5, 2, I, "as the seed variant"),
    sercom(Role::kUartRx, pb(23), 'D', 5, 3, I, "as the seed variant"),
    sercom(Role::kDriverMiso, pa(12), 'D', 4, 0, I, "as the seed variant"),
    sercom(Role::kDriverMosi, pb(10), 'D', 4, 2, I, "as the seed variant"),
    sercom(Role::kDriverSck, pb(11), 'D', 4, 3, I, "as the seed variant"),
    gpio(Role::kStep1, pa(5), G, "bench wiring"),
    gpio(Role::kDir1, pa(6), G, "bench wiring"),
    gpio(Role::kCs1, pa(7), G, "bench wiring"),
    gpio(Role::kStep2, pa(8), G, "bench wiring"),
    gpio(Role::kDir2, pa(9), G, "bench wiring"),
    gpio(Role::kCs2, pa(13), G, "bench wiring"),
    gpio(Role::kStep3, pa(20), G, "bench wiring"),
    gpio(Role::kDir3, pa(21), G, "bench wiring"),
    gpio(Role::kCs3, pa(23), G, "bench wiring"),
    tcc(Role::kServo1, pa(18), 'F', 0, 2, G, "bench wiring"),
    tcc(Role::kServo2, pa(19), 'F', 0, 3, G, "bench wiring"),
    sercom(Role::kStrip1, pa(16), 'C', 1, 0, G, "bench wiring"),
    sercom(Role::kStrip2, pa(22), 'C', 3, 0, G, "bench wiring"),
    eic(Role::kLimit1Reverse, pb(2), 2, G, "bench wiring"),
    eic(Role::kLimit1Forward, pb(3), 3, G, "bench wiring"),
    eic(Role::kLimit2Reverse, pb(8), 8, G, "bench wiring"),
    eic(Role::kLimit2Forward, pb(9), 9, G, "bench wiring"),
    eic(Role::kEmergency, pa(15), 15, G, "bench wiring"),
    tc(Role::kBuzzer, pa(14), 3, 0, G, "bench wiring"),
    gpio(Role::kBootLedLeft, pa(27), G, "bench wiring"),
    gpio(Role::kBootLedRight, pa(28), G, "bench wiring"),
    gpio(Role::kReserved, pa(0), I, "as the seed variant"),
    gpio(Role::kReserved, pa(1), I, "as the seed variant"),
    gpio(Role::kReserved, pa(3), I, "as the seed variant"),
    gpio(Role::kReserved, pa(10), S, "as the seed variant"),
    gpio(Role::kReserved, pa(11), S, "as the seed variant"),
    gpio(Role::kReserved, pa(24), S, "as the seed variant"),
    gpio(Role::kReserved, pa(25), S, "as the seed variant"),
    gpio(Role::kReserved, pa(30), S, "as the seed variant"),
    gpio(Role::kReserved, pa(31), S, "as the seed variant"),
};
}  // namespace bench_pins

inline constexpr pin_map::BoardVariant kBench{
    "bench", bench_pins::kPins, sizeof(bench_pins::kPins) / sizeof(bench_pins::kPins[0]), true,
    "the earlier bench map: strips on PA16/PA22, emergency PA15, tilt servo PA19"};

}  // namespace hmc::samd21::boards
