// The pin table's vocabulary and its checks. A board variant (boards/*.h) is one table: every
// pin the board uses or keeps free, once, with the peripheral signal it carries and the
// evidence for it — sourced (a document about this board says so), inferred (follows from what
// the seed's firmware uses, e.g. a library that works on those pins only) or guessed (nothing
// says so: a free pin this port chose). board.h reads the selected variant's table; the checks
// below run on it at compile time (board.h) and on every variant in pin_map_test.cpp, against
// the datasheet's multiplexing table (port_functions.h).
//
// Freestanding: <stdint.h> only, so the host test can include it.
#pragma once

#include <stdint.h>

#include "port_functions.h"

namespace hmc::samd21::pin_map {

using port_functions::Unit;

// A port pin: group 0 = PA, 1 = PB.
struct Pin {
  uint8_t group;
  uint8_t number;
};
constexpr Pin pa(uint8_t n) { return Pin{0, n}; }
constexpr Pin pb(uint8_t n) { return Pin{1, n}; }
constexpr bool operator==(Pin a, Pin b) { return a.group == b.group && a.number == b.number; }

// What a pin does on the board.
enum class Role : uint8_t {
  kUartTx, kUartRx,                        // command UART to the FT232RL
  kDriverMiso, kDriverMosi, kDriverSck,    // the DRV8711 SPI bus
  kStep1, kDir1, kCs1, kStep2, kDir2, kCs2, kStep3, kDir3, kCs3,
  kServo1, kServo2,                        // pan, tilt
  kStrip1, kStrip2,                        // SK6812 data
  kLimit1Reverse, kLimit1Forward, kLimit2Reverse, kLimit2Forward,
  kEmergency,
  kBuzzer,
  kBootLedLeft, kBootLedRight,
  kReserved,  // kept free for something else on the chip (crystal, USB, SWD, ...)
};
inline constexpr uint32_t kRoleCount = static_cast<uint32_t>(Role::kReserved);  // roles used once

constexpr const char* role_name(Role r) {
  constexpr const char* kNames[] = {
      "uart_tx", "uart_rx", "driver_miso", "driver_mosi", "driver_sck",
      "step1", "dir1", "cs1", "step2", "dir2", "cs2", "step3", "dir3", "cs3",
      "servo1", "servo2", "strip1", "strip2",
      "limit1_reverse", "limit1_forward", "limit2_reverse", "limit2_forward",
      "emergency", "buzzer", "boot_led_left", "boot_led_right", "reserved"};
  return kNames[static_cast<uint32_t>(r)];
}

enum class Evidence : uint8_t { kSourced, kInferred, kGuessed };

constexpr const char* evidence_name(Evidence e) {
  return e == Evidence::kSourced ? "sourced" : e == Evidence::kInferred ? "inferred" : "guessed";
}

// One row: the pin, its role, the PMUX function (0: a plain GPIO, no peripheral) with the unit,
// instance and index it connects to, and the evidence with its reason.
struct PinAssignment {
  Role role;
  Pin pin;
  char function;  // 'A'..'F', or 0
  Unit unit;
  uint8_t instance;
  uint8_t index;
  Evidence evidence;
  const char* why;
};

constexpr PinAssignment gpio(Role r, Pin p, Evidence e, const char* why) {
  return {r, p, 0, Unit::kEic, 0, 0, e, why};
}
constexpr PinAssignment eic(Role r, Pin p, uint8_t line, Evidence e, const char* why) {
  return {r, p, 'A', Unit::kEic, 0, line, e, why};
}
constexpr PinAssignment sercom(Role r, Pin p, char function, uint8_t n, uint8_t pad, Evidence e, const char* why) {
  return {r, p, function, Unit::kSercom, n, pad, e, why};
}
constexpr PinAssignment tc(Role r, Pin p, uint8_t n, uint8_t wo, Evidence e, const char* why) {
  return {r, p, 'E', Unit::kTc, n, wo, e, why};
}
constexpr PinAssignment tcc(Role r, Pin p, char function, uint8_t n, uint8_t wo, Evidence e, const char* why) {
  return {r, p, function, Unit::kTcc, n, wo, e, why};
}

// A board variant: its name (HMC_BOARD, embedded in the image) and its table.
struct BoardVariant {
  const char* name;
  const PinAssignment* pins;
  uint32_t count;
  bool switches_active_low;  // switches close to ground (pull-up on): pressed reads low
  const char* summary;
};

constexpr bool same_text(const char* a, const char* b) {
  while (*a != '\0' && *a == *b) {
    ++a;
    ++b;
  }
  return *a == *b;
}

// The row for a role (nullptr: none).
constexpr const PinAssignment* find(const BoardVariant& v, Role r) {
  for (uint32_t i = 0; i < v.count; ++i) {
    if (v.pins[i].role == r) return &v.pins[i];
  }
  return nullptr;
}

// SPI DOPO for a data-out pad and a clock pad (SAMD21 datasheet, SERCOM SPI, CTRLA.DOPO):
// 0 DO PAD0 SCK PAD1, 1 DO PAD2 SCK PAD3, 2 DO PAD3 SCK PAD1, 3 DO PAD0 SCK PAD3; -1: none.
constexpr int spi_dopo(uint32_t data_pad, uint32_t clock_pad) {
  if (data_pad == 0 && clock_pad == 1) return 0;
  if (data_pad == 2 && clock_pad == 3) return 1;
  if (data_pad == 3 && clock_pad == 1) return 2;
  if (data_pad == 0 && clock_pad == 3) return 3;
  return -1;
}
// A data-out-only bus (the LED strips) leaves its clock pad unrouted: the DOPO that puts DO on
// the pad (PAD0 → 0, PAD2 → 1, PAD3 → 2; PAD1 cannot carry DO: -1).
constexpr int spi_dopo_data_only(uint32_t data_pad) {
  return data_pad == 0 ? 0 : data_pad == 2 ? 1 : data_pad == 3 ? 2 : -1;
}
// USART TXPO for a TX pad (CTRLA.TXPO: 0 TX on PAD0, 1 TX on PAD2; -1: none).
constexpr int usart_txpo(uint32_t tx_pad) { return tx_pad == 0 ? 0 : tx_pad == 2 ? 1 : -1; }

// The first thing wrong with a variant's table, and the row (or role) it concerns.
struct Problem {
  const char* what;  // nullptr: the table is sound
  uint32_t row;
};

constexpr bool role_is_gpio(Role r) {
  return (r >= Role::kStep1 && r <= Role::kCs3) || r == Role::kBootLedLeft || r == Role::kBootLedRight ||
         r == Role::kReserved;
}
constexpr bool role_is_switch(Role r) { return r >= Role::kLimit1Reverse && r <= Role::kEmergency; }

constexpr Problem check(const BoardVariant& v) {
  // Each row on its own.
  for (uint32_t i = 0; i < v.count; ++i) {
    const PinAssignment& a = v.pins[i];
    if (!port_functions::pin_exists(a.pin.group, a.pin.number)) return {"pin does not exist on the SAMD21G18", i};
    if (a.why == nullptr || a.why[0] == '\0') return {"row gives no reason for its evidence", i};
    for (uint32_t j = 0; j < i; ++j) {
      if (v.pins[j].pin == a.pin) return {"pin appears twice", i};
    }
    if (a.function != 0 &&
        !port_functions::pin_has(a.pin.group, a.pin.number, a.function, a.unit, a.instance, a.index)) {
      return {"peripheral function not available on this pin (datasheet Table 7-1)", i};
    }
    if (role_is_gpio(a.role) && a.function != 0) return {"a GPIO role has a peripheral function", i};
    if (role_is_switch(a.role) && (a.function != 'A' || a.unit != Unit::kEic)) {
      return {"a switch must be on an EXTINT line (function A)", i};
    }
    if ((a.role == Role::kServo1 || a.role == Role::kServo2) && (a.unit != Unit::kTcc || a.instance != 0)) {
      return {"a servo must be on a TCC0 output (servo_pwm.cpp drives TCC0)", i};
    }
    if (a.role == Role::kBuzzer && (a.unit != Unit::kTc || a.instance != 3 || a.index != 0)) {
      return {"the buzzer must be on TC3 WO[0] (buzzer.cpp toggles WO[0] in frequency mode)", i};
    }
    const bool on_sercom = a.role <= Role::kDriverSck || a.role == Role::kStrip1 || a.role == Role::kStrip2;
    if (on_sercom && (a.function == 0 || a.unit != Unit::kSercom)) return {"a bus role must be on a SERCOM pad", i};
  }
  // Each role once.
  for (uint32_t r = 0; r < kRoleCount; ++r) {
    uint32_t seen = 0;
    for (uint32_t i = 0; i < v.count; ++i) seen += v.pins[i].role == static_cast<Role>(r) ? 1u : 0u;
    if (seen != 1) return {seen == 0 ? "a role has no pin" : "a role has several pins", r};
  }
  const PinAssignment& tx = *find(v, Role::kUartTx);
  const PinAssignment& rx = *find(v, Role::kUartRx);
  const PinAssignment& miso = *find(v, Role::kDriverMiso);
  const PinAssignment& mosi = *find(v, Role::kDriverMosi);
  const PinAssignment& sck = *find(v, Role::kDriverSck);
  const PinAssignment& strip1 = *find(v, Role::kStrip1);
  const PinAssignment& strip2 = *find(v, Role::kStrip2);
  // SERCOM pads: each bus on one SERCOM, pads the mode can use, one SERCOM per bus.
  if (rx.instance != tx.instance) return {"UART TX and RX are on different SERCOMs", 0};
  if (usart_txpo(tx.index) < 0) return {"UART TX must be on PAD0 or PAD2 (TXPO)", 0};
  if (rx.index == tx.index) return {"UART RX and TX on one pad", 0};
  if (miso.instance != mosi.instance || sck.instance != mosi.instance) return {"SPI pins on different SERCOMs", 0};
  if (spi_dopo(mosi.index, sck.index) < 0) return {"SPI MOSI/SCK pads match no DOPO setting", 0};
  if (miso.index == mosi.index || miso.index == sck.index) return {"SPI MISO pad collides with MOSI or SCK", 0};
  const PinAssignment* const strips[] = {&strip1, &strip2};
  for (const PinAssignment* strip : strips) {
    if (spi_dopo_data_only(strip->index) < 0) return {"an LED strip's data pad cannot carry SPI DO", 0};
    if (strip->instance == tx.instance || strip->instance == mosi.instance) {
      return {"an LED strip shares its SERCOM with another bus", 0};
    }
  }
  if (strip1.instance == strip2.instance) return {"both LED strips on one SERCOM", 0};
  if (tx.instance == mosi.instance) return {"UART and SPI on one SERCOM", 0};
  // STEP: the DMAC raises and lowers every driver's STEP pin with one OUTSET and one OUTCLR
  // write (step_pulses.h): one port group.
  if (find(v, Role::kStep2)->pin.group != find(v, Role::kStep1)->pin.group ||
      find(v, Role::kStep3)->pin.group != find(v, Role::kStep1)->pin.group) {
    return {"the STEP pins are in more than one port group (one DMA write raises them)", 0};
  }
  // EXTINT lines and TCC channels: one per signal.
  for (uint32_t i = 0; i < v.count; ++i) {
    for (uint32_t j = 0; j < i; ++j) {
      const PinAssignment& a = v.pins[i];
      const PinAssignment& b = v.pins[j];
      if (role_is_switch(a.role) && role_is_switch(b.role) && a.index == b.index) {
        return {"two switches on one EXTINT line", i};
      }
      const bool servos = (a.role == Role::kServo1 || a.role == Role::kServo2) &&
                          (b.role == Role::kServo1 || b.role == Role::kServo2);
      if (servos && a.index % 4 == b.index % 4) return {"both servos on one TCC0 compare channel (WO[n] follows CC[n % 4])", i};
    }
  }
  return {nullptr, 0};
}

// "PA05", "PB10".
struct PinName {
  char text[5];
};
constexpr PinName pin_name(Pin p) {
  return {{'P', p.group == 0 ? 'A' : 'B', static_cast<char>('0' + p.number / 10),
           static_cast<char>('0' + p.number % 10), '\0'}};
}

// The text the image carries so `hmc flash` can name the variant, the protocol and firmware
// versions to expect from the board, and the unverified pins:
// "hmc-board:<name>;protocol:<n>;firmware:<n>;guessed:PA05,PA06,...;" and zeros after it.
inline constexpr char kInfoMarker[] = "hmc-board:";
struct InfoText {
  char text[256];
};
constexpr InfoText info_text(const BoardVariant& v, uint32_t protocol, uint32_t firmware) {
  InfoText out{};
  uint32_t at = 0;
  auto put = [&out, &at](const char* s) {
    while (*s != '\0' && at + 1 < sizeof(out.text)) out.text[at++] = *s++;
  };
  auto put_number = [&put](uint32_t n) {
    char digits[11] = {};
    int i = 10;
    do {
      digits[--i] = static_cast<char>('0' + n % 10);
      n /= 10;
    } while (n != 0);
    put(digits + i);
  };
  put(kInfoMarker);
  put(v.name);
  put(";protocol:");
  put_number(protocol);
  put(";firmware:");
  put_number(firmware);
  put(";guessed:");
  bool first = true;
  for (uint32_t i = 0; i < v.count; ++i) {
    if (v.pins[i].evidence != Evidence::kGuessed) continue;
    if (!first) put(",");
    first = false;
    put(pin_name(v.pins[i].pin).text);
  }
  put(";");
  return out;
}

}  // namespace hmc::samd21::pin_map
