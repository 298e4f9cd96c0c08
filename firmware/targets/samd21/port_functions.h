// Which peripheral signal each SAMD21G18 pin can carry, per PMUX function: the datasheet's
// "PORT Function Multiplexing" table (SAMD21 family datasheet DS40001882, section 7.1
// "Multiplexed Signals", Table 7-1), transcribed for the 38 I/O pins of the 48-pin G package and
// the functions this port can use: A (EIC), C (SERCOM), D (SERCOM-ALT), E (TC/TCC), F (TCC).
// B (analog), G (I2S, USB, SWD) and H (GCLK, AC) are left out: nothing here uses them. TC6 and
// TC7 exist only on the 64-pin J package and are left out too. PA08's function A is NMI, not an
// EXTINT line. Cross-checked against the pin descriptions of ArduinoCore-samd's Arduino Zero
// variant (variant.cpp) and Adafruit_NeoPixel_ZeroDMA's pin table for the rows they cover
// (pin_map_test.cpp).
//
// Used by the pin table's checks (pin_map.h, pin_map_test.cpp) on the host and in the firmware
// build; nothing reads it at run time. Freestanding: <stdint.h> only.
#pragma once

#include <stdint.h>

namespace hmc::samd21::port_functions {

enum class Unit : uint8_t { kEic, kSercom, kTc, kTcc };

// One entry of the table: on pin (group, number), function `letter` ('A'..'F') connects the
// pin to `unit` instance `instance`, signal `index` (EXTINT line, SERCOM pad, or WO output).
struct Signal {
  uint8_t group;  // 0 = PA, 1 = PB
  uint8_t number;
  char letter;
  Unit unit;
  uint8_t instance;  // SERCOMn, TCn, TCCn; 0 for the EIC
  uint8_t index;     // EXTINT[index], PAD[index], WO[index]
};

#define HMC_EIC(g, n, line) {g, n, 'A', Unit::kEic, 0, line}
#define HMC_SC(g, n, sercom, pad) {g, n, 'C', Unit::kSercom, sercom, pad}
#define HMC_SD(g, n, sercom, pad) {g, n, 'D', Unit::kSercom, sercom, pad}
#define HMC_TE(g, n, tc, wo) {g, n, 'E', Unit::kTc, tc, wo}
#define HMC_TCCE(g, n, tcc, wo) {g, n, 'E', Unit::kTcc, tcc, wo}
#define HMC_TCCF(g, n, tcc, wo) {g, n, 'F', Unit::kTcc, tcc, wo}

inline constexpr Signal kSignals[] = {
    HMC_EIC(0, 0, 0), HMC_SD(0, 0, 1, 0), HMC_TCCE(0, 0, 2, 0),
    HMC_EIC(0, 1, 1), HMC_SD(0, 1, 1, 1), HMC_TCCE(0, 1, 2, 1),
    HMC_EIC(0, 2, 2),
    HMC_EIC(0, 3, 3),
    HMC_EIC(0, 4, 4), HMC_SD(0, 4, 0, 0), HMC_TCCE(0, 4, 0, 0),
    HMC_EIC(0, 5, 5), HMC_SD(0, 5, 0, 1), HMC_TCCE(0, 5, 0, 1),
    HMC_EIC(0, 6, 6), HMC_SD(0, 6, 0, 2), HMC_TCCE(0, 6, 1, 0),
    HMC_EIC(0, 7, 7), HMC_SD(0, 7, 0, 3), HMC_TCCE(0, 7, 1, 1),
    /* PA08: A is NMI */ HMC_SC(0, 8, 0, 0), HMC_SD(0, 8, 2, 0), HMC_TCCE(0, 8, 0, 0), HMC_TCCF(0, 8, 1, 2),
    HMC_EIC(0, 9, 9), HMC_SC(0, 9, 0, 1), HMC_SD(0, 9, 2, 1), HMC_TCCE(0, 9, 0, 1), HMC_TCCF(0, 9, 1, 3),
    HMC_EIC(0, 10, 10), HMC_SC(0, 10, 0, 2), HMC_SD(0, 10, 2, 2), HMC_TCCE(0, 10, 1, 0), HMC_TCCF(0, 10, 0, 2),
    HMC_EIC(0, 11, 11), HMC_SC(0, 11, 0, 3), HMC_SD(0, 11, 2, 3), HMC_TCCE(0, 11, 1, 1), HMC_TCCF(0, 11, 0, 3),
    HMC_EIC(0, 12, 12), HMC_SC(0, 12, 2, 0), HMC_SD(0, 12, 4, 0), HMC_TCCE(0, 12, 2, 0), HMC_TCCF(0, 12, 0, 6),
    HMC_EIC(0, 13, 13), HMC_SC(0, 13, 2, 1), HMC_SD(0, 13, 4, 1), HMC_TCCE(0, 13, 2, 1), HMC_TCCF(0, 13, 0, 7),
    HMC_EIC(0, 14, 14), HMC_SC(0, 14, 2, 2), HMC_SD(0, 14, 4, 2), HMC_TE(0, 14, 3, 0), HMC_TCCF(0, 14, 0, 4),
    HMC_EIC(0, 15, 15), HMC_SC(0, 15, 2, 3), HMC_SD(0, 15, 4, 3), HMC_TE(0, 15, 3, 1), HMC_TCCF(0, 15, 0, 5),
    HMC_EIC(0, 16, 0), HMC_SC(0, 16, 1, 0), HMC_SD(0, 16, 3, 0), HMC_TCCE(0, 16, 2, 0), HMC_TCCF(0, 16, 0, 6),
    HMC_EIC(0, 17, 1), HMC_SC(0, 17, 1, 1), HMC_SD(0, 17, 3, 1), HMC_TCCE(0, 17, 2, 1), HMC_TCCF(0, 17, 0, 7),
    HMC_EIC(0, 18, 2), HMC_SC(0, 18, 1, 2), HMC_SD(0, 18, 3, 2), HMC_TE(0, 18, 3, 0), HMC_TCCF(0, 18, 0, 2),
    HMC_EIC(0, 19, 3), HMC_SC(0, 19, 1, 3), HMC_SD(0, 19, 3, 3), HMC_TE(0, 19, 3, 1), HMC_TCCF(0, 19, 0, 3),
    HMC_EIC(0, 20, 4), HMC_SC(0, 20, 5, 2), HMC_SD(0, 20, 3, 2), HMC_TCCF(0, 20, 0, 6),
    HMC_EIC(0, 21, 5), HMC_SC(0, 21, 5, 3), HMC_SD(0, 21, 3, 3), HMC_TCCF(0, 21, 0, 7),
    HMC_EIC(0, 22, 6), HMC_SC(0, 22, 3, 0), HMC_SD(0, 22, 5, 0), HMC_TE(0, 22, 4, 0), HMC_TCCF(0, 22, 0, 4),
    HMC_EIC(0, 23, 7), HMC_SC(0, 23, 3, 1), HMC_SD(0, 23, 5, 1), HMC_TE(0, 23, 4, 1), HMC_TCCF(0, 23, 0, 5),
    HMC_EIC(0, 24, 12), HMC_SC(0, 24, 3, 2), HMC_SD(0, 24, 5, 2), HMC_TE(0, 24, 5, 0), HMC_TCCF(0, 24, 1, 2),
    HMC_EIC(0, 25, 13), HMC_SC(0, 25, 3, 3), HMC_SD(0, 25, 5, 3), HMC_TE(0, 25, 5, 1), HMC_TCCF(0, 25, 1, 3),
    HMC_EIC(0, 27, 15),
    HMC_EIC(0, 28, 8),
    HMC_EIC(0, 30, 10), HMC_SD(0, 30, 1, 2), HMC_TCCE(0, 30, 1, 0),
    HMC_EIC(0, 31, 11), HMC_SD(0, 31, 1, 3), HMC_TCCE(0, 31, 1, 1),
    HMC_EIC(1, 2, 2), HMC_SD(1, 2, 5, 0),
    HMC_EIC(1, 3, 3), HMC_SD(1, 3, 5, 1),
    HMC_EIC(1, 8, 8), HMC_SD(1, 8, 4, 0), HMC_TE(1, 8, 4, 0),
    HMC_EIC(1, 9, 9), HMC_SD(1, 9, 4, 1), HMC_TE(1, 9, 4, 1),
    HMC_EIC(1, 10, 10), HMC_SD(1, 10, 4, 2), HMC_TE(1, 10, 5, 0), HMC_TCCF(1, 10, 0, 4),
    HMC_EIC(1, 11, 11), HMC_SD(1, 11, 4, 3), HMC_TE(1, 11, 5, 1), HMC_TCCF(1, 11, 0, 5),
    HMC_EIC(1, 22, 6), HMC_SD(1, 22, 5, 2),
    HMC_EIC(1, 23, 7), HMC_SD(1, 23, 5, 3),
};

#undef HMC_EIC
#undef HMC_SC
#undef HMC_SD
#undef HMC_TE
#undef HMC_TCCE
#undef HMC_TCCF

// Whether the pin exists on the SAMD21G18 (the 48-pin package): PA00-PA25, PA27, PA28, PA30,
// PA31, PB02, PB03, PB08-PB11, PB22, PB23.
constexpr bool pin_exists(uint8_t group, uint8_t number) {
  if (group == 0) return number <= 25 || number == 27 || number == 28 || number == 30 || number == 31;
  if (group == 1) {
    return number == 2 || number == 3 || (number >= 8 && number <= 11) || number == 22 || number == 23;
  }
  return false;
}

// Whether function `letter` on the pin connects it to unit/instance/index.
constexpr bool pin_has(uint8_t group, uint8_t number, char letter, Unit unit, uint8_t instance, uint8_t index) {
  for (const Signal& s : kSignals) {
    if (s.group == group && s.number == number && s.letter == letter && s.unit == unit && s.instance == instance &&
        s.index == index) {
      return true;
    }
  }
  return false;
}

}  // namespace hmc::samd21::port_functions
