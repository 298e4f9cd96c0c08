// The board variants' pin tables (boards/*.h) against their checks (pin_map.h) and the
// datasheet's multiplexing table (port_functions.h); broken tables, each with one fault, are
// caught; the image's board info text; docs/firmware.md's pin map is the seed variant's table.
#include <catch2/catch.hpp>

#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "boards/boards.h"
#include "pin_map.h"
#include "port_functions.h"

namespace {

using namespace hmc::samd21;
using namespace hmc::samd21::pin_map;

std::string problem_of(const BoardVariant& v) {
  const Problem p = check(v);
  return p.what == nullptr ? "" : std::string(p.what) + " (row " + std::to_string(p.row) + ")";
}

// The seed table with one row changed.
struct Edited {
  std::vector<PinAssignment> rows;
  BoardVariant variant;
  explicit Edited(void (*edit)(std::vector<PinAssignment>&))
      : rows(boards::kSeed.pins, boards::kSeed.pins + boards::kSeed.count), variant(boards::kSeed) {
    edit(rows);
    variant.pins = rows.data();
    variant.count = static_cast<uint32_t>(rows.size());
  }
};

PinAssignment& row_of(std::vector<PinAssignment>& rows, Role r) {
  for (auto& a : rows) {
    if (a.role == r) return a;
  }
  throw std::logic_error("no row");
}

std::string pin_text(Pin p) { return pin_name(p).text; }

}  // namespace

TEST_CASE("every board variant passes the pin table's checks") {
  for (const BoardVariant* v : boards::kVariants) {
    INFO(v->name);
    CHECK(problem_of(*v).empty());
    CHECK(boards::find_variant(v->name) == v);
  }
  CHECK(boards::find_variant(boards::kDefaultVariant) == &boards::kSeed);
  CHECK(boards::find_variant("nonesuch") == nullptr);
}

TEST_CASE("the seed variant puts the LED strips where Adafruit_NeoPixel_ZeroDMA can drive them") {
  const PinAssignment& s1 = *find(boards::kSeed, Role::kStrip1);
  const PinAssignment& s2 = *find(boards::kSeed, Role::kStrip2);
  CHECK(pin_text(s1.pin) == "PA15");
  CHECK(pin_text(s2.pin) == "PA19");
  // The library's rows for the Zero / Feather M0: (SERCOM, pad, function) per pin.
  CHECK((s1.instance == 2 && s1.index == 3 && s1.function == 'C'));
  CHECK((s2.instance == 1 && s2.index == 3 && s2.function == 'C'));
  CHECK(s1.evidence == Evidence::kInferred);
  CHECK(pin_text(find(boards::kSeed, Role::kEmergency)->pin) != "PA15");
  CHECK(pin_text(find(boards::kSeed, Role::kServo2)->pin) != "PA19");
}

TEST_CASE("the multiplexing table agrees with the rows the libraries rely on") {
  using port_functions::pin_has;
  using port_functions::Unit;
  // Adafruit_NeoPixel_ZeroDMA's Zero/Feather M0 rows.
  CHECK(pin_has(0, 19, 'C', Unit::kSercom, 1, 3));
  CHECK(pin_has(0, 15, 'C', Unit::kSercom, 2, 3));
  CHECK(pin_has(1, 10, 'D', Unit::kSercom, 4, 2));
  CHECK(pin_has(0, 20, 'C', Unit::kSercom, 5, 2));
  // The Zero variant's Serial5 and SPI.
  CHECK(pin_has(1, 22, 'D', Unit::kSercom, 5, 2));
  CHECK(pin_has(1, 23, 'D', Unit::kSercom, 5, 3));
  CHECK(pin_has(0, 12, 'D', Unit::kSercom, 4, 0));
  CHECK(pin_has(1, 11, 'D', Unit::kSercom, 4, 3));
  // ArduinoCore-samd variants/arduino_zero/variant.cpp, its pin descriptions (timer STD = E,
  // ALT = F; SERCOM STD = C, ALT = D; the EXTINT line).
  CHECK(pin_has(0, 8, 'E', Unit::kTcc, 0, 0));
  CHECK(pin_has(0, 8, 'D', Unit::kSercom, 2, 0));
  CHECK(pin_has(0, 9, 'E', Unit::kTcc, 0, 1));
  CHECK(pin_has(0, 9, 'A', Unit::kEic, 0, 9));
  CHECK(pin_has(0, 10, 'C', Unit::kSercom, 0, 2));
  CHECK(pin_has(0, 15, 'E', Unit::kTc, 3, 1));
  CHECK(pin_has(0, 15, 'A', Unit::kEic, 0, 15));
  CHECK(pin_has(0, 16, 'E', Unit::kTcc, 2, 0));
  CHECK(pin_has(0, 16, 'A', Unit::kEic, 0, 0));
  CHECK(pin_has(0, 17, 'C', Unit::kSercom, 1, 1));
  CHECK(pin_has(0, 18, 'E', Unit::kTc, 3, 0));
  CHECK(pin_has(0, 18, 'C', Unit::kSercom, 1, 2));
  CHECK(pin_has(0, 19, 'F', Unit::kTcc, 0, 3));
  CHECK(pin_has(0, 20, 'F', Unit::kTcc, 0, 6));
  CHECK(pin_has(0, 20, 'A', Unit::kEic, 0, 4));
  CHECK(pin_has(0, 22, 'E', Unit::kTc, 4, 0));
  CHECK(pin_has(0, 22, 'A', Unit::kEic, 0, 6));
  CHECK(pin_has(0, 6, 'E', Unit::kTcc, 1, 0));
  CHECK(pin_has(1, 10, 'E', Unit::kTc, 5, 0));
  CHECK(pin_has(1, 8, 'A', Unit::kEic, 0, 8));
  // PA08's function A is NMI, no EXTINT line; PA26 and PA29 do not exist.
  for (uint8_t line = 0; line < 16; ++line) CHECK_FALSE(pin_has(0, 8, 'A', Unit::kEic, 0, line));
  CHECK_FALSE(port_functions::pin_exists(0, 26));
  CHECK_FALSE(port_functions::pin_exists(0, 29));
  CHECK_FALSE(port_functions::pin_exists(1, 4));
  // No (pin, function) pair twice in the transcription.
  const auto& t = port_functions::kSignals;
  for (std::size_t i = 0; i < std::size(t); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      INFO("entries " << j << " and " << i);
      CHECK_FALSE((t[i].group == t[j].group && t[i].number == t[j].number && t[i].letter == t[j].letter));
    }
    CHECK(port_functions::pin_exists(t[i].group, t[i].number));
  }
}

// The rows the strips, servos and buzzer use, against a second transcription of the datasheet's
// multiplexing table: Microchip's SAMD21 device headers (include/pio/samd21*.h of the device
// pack, Apache-2.0), whose PIN_<pin><function>_<signal> / MUX_<...> macros give the function as
// a number, A = 0 ... H = 7: MUX_PA15C_SERCOM2_PAD3 2, MUX_PA19C_SERCOM1_PAD3 2,
// MUX_PA18F_TCC0_WO2 5, MUX_PA22F_TCC0_WO4 5, MUX_PA14E_TC3_WO0 4. hmc-emu routes these signals
// to the strips, servos and buzzer through the same table (emu/chip/port.cpp).
TEST_CASE("the seed's strip, servo and buzzer pins carry the signals Microchip's pin headers name") {
  struct HeaderRow {
    Role role;
    Pin pin;
    uint32_t mux;  // MUX_... value
    port_functions::Unit unit;
    uint8_t instance, index;
  };
  const HeaderRow rows[] = {
      {Role::kStrip1, pa(15), 2, port_functions::Unit::kSercom, 2, 3},
      {Role::kStrip2, pa(19), 2, port_functions::Unit::kSercom, 1, 3},
      {Role::kServo1, pa(18), 5, port_functions::Unit::kTcc, 0, 2},
      {Role::kServo2, pa(22), 5, port_functions::Unit::kTcc, 0, 4},
      {Role::kBuzzer, pa(14), 4, port_functions::Unit::kTc, 3, 0},
  };
  for (const HeaderRow& h : rows) {
    INFO(role_name(h.role));
    const PinAssignment& a = *find(boards::kSeed, h.role);
    CHECK(a.pin == h.pin);
    CHECK(static_cast<uint32_t>(a.function - 'A') == h.mux);
    CHECK((a.unit == h.unit && a.instance == h.instance && a.index == h.index));
    CHECK(port_functions::pin_has(h.pin.group, h.pin.number, static_cast<char>('A' + h.mux), h.unit, h.instance,
                                  h.index));
  }
  // The strips' data on PAD3 needs DOPO 2 (DO on PAD3); the servos' WO[2] and WO[4] follow CC2
  // and CC0 (WO[n] follows CC[n % 4]), two different compare channels.
  CHECK(spi_dopo_data_only(3) == 2);
  CHECK(find(boards::kSeed, Role::kServo1)->index % 4 != find(boards::kSeed, Role::kServo2)->index % 4);
}

TEST_CASE("a broken table is refused, naming what is wrong") {
  SECTION("a pin twice") {
    Edited e([](auto& rows) { row_of(rows, Role::kEmergency).pin = pa(15); });
    CHECK(problem_of(e.variant).find("pin appears twice") == 0);
  }
  SECTION("a function the pin does not have") {
    Edited e([](auto& rows) { row_of(rows, Role::kServo2).index = 3; });  // PA22 has no TCC0 WO[3]
    CHECK(problem_of(e.variant).find("peripheral function not available") == 0);
  }
  SECTION("a pin the package lacks") {
    Edited e([](auto& rows) { row_of(rows, Role::kStep1).pin = pa(26); });
    CHECK(problem_of(e.variant).find("pin does not exist") == 0);
  }
  SECTION("a role without a pin") {
    Edited e([](auto& rows) { row_of(rows, Role::kBootLedLeft).role = Role::kReserved; });
    CHECK(problem_of(e.variant).find("a role has no pin") == 0);
  }
  SECTION("a role with two pins") {
    Edited e([](auto& rows) { row_of(rows, Role::kBootLedLeft).role = Role::kStep1; });
    CHECK(problem_of(e.variant).find("a role has several pins") == 0);
  }
  SECTION("SPI pads that match no DOPO") {
    Edited e([](auto& rows) {
      auto& sck = row_of(rows, Role::kDriverSck);  // PB11 -> PB09: SERCOM4 PAD1, beside MOSI's PAD2
      sck.pin = pb(9);
      sck.index = 1;
      row_of(rows, Role::kLimit2Forward).pin = pb(11);
      row_of(rows, Role::kLimit2Forward).index = 11;
    });
    CHECK(problem_of(e.variant) == "SPI MOSI/SCK pads match no DOPO setting (row 0)");
  }
  SECTION("UART pins on different SERCOMs") {
    Edited e([](auto& rows) {
      auto& rx = row_of(rows, Role::kUartRx);  // PB23 -> PA21: SERCOM5 PAD3 via C, then SERCOM3 via D
      rx.pin = pa(21);
      rx.function = 'D';
      rx.instance = 3;
      row_of(rows, Role::kDir3).pin = pb(23);
    });
    CHECK(problem_of(e.variant) == "UART TX and RX are on different SERCOMs (row 0)");
  }
  SECTION("an LED strip on a pad that cannot carry DO") {
    Edited e([](auto& rows) {
      auto& strip = row_of(rows, Role::kStrip1);  // PA13: SERCOM2 PAD1
      strip.pin = pa(13);
      strip.index = 1;
      row_of(rows, Role::kCs2).pin = pa(15);
    });
    CHECK(problem_of(e.variant) == "an LED strip's data pad cannot carry SPI DO (row 0)");
  }
  SECTION("two switches on one EXTINT line") {
    Edited e([](auto& rows) {
      auto& em = row_of(rows, Role::kEmergency);  // PA02 is EXTINT2, as PB02
      em.pin = pa(2);
      em.index = 2;
    });
    CHECK(problem_of(e.variant).find("two switches on one EXTINT line") == 0);
  }
  SECTION("STEP pins in two port groups") {
    Edited e([](auto& rows) {
      row_of(rows, Role::kStep3).pin = pb(2);  // PA20 <-> PB02 (EXTINT2; PA20 is EXTINT4)
      auto& limit = row_of(rows, Role::kLimit1Reverse);
      limit.pin = pa(20);
      limit.index = 4;
    });
    CHECK(problem_of(e.variant) == "the STEP pins are in more than one port group (one DMA write raises them) (row 0)");
  }
  SECTION("both servos on one compare channel") {
    Edited e([](auto& rows) {
      auto& tilt = row_of(rows, Role::kServo2);  // PA16 is TCC0 WO[6]: CC2, as the pan servo's WO[2]
      tilt.pin = pa(16);
      tilt.index = 6;
      row_of(rows, Role::kEmergency).pin = pa(22);
      row_of(rows, Role::kEmergency).index = 6;
    });
    CHECK(problem_of(e.variant).find("both servos on one TCC0 compare channel") == 0);
  }
}

TEST_CASE("the image's board info names the variant and every guessed pin") {
  const std::string seed = info_text(boards::kSeed, 4, 100).text;
  CHECK(seed.rfind("hmc-board:seed;protocol:4;firmware:100;guessed:PA05,PA06,", 0) == 0);
  CHECK(seed.back() == ';');
  uint32_t guessed = 0;
  for (uint32_t i = 0; i < boards::kSeed.count; ++i) {
    const std::string name = pin_text(boards::kSeed.pins[i].pin);
    const bool listed = seed.find(name) != std::string::npos;
    INFO(name);
    CHECK(listed == (boards::kSeed.pins[i].evidence == Evidence::kGuessed));
    guessed += boards::kSeed.pins[i].evidence == Evidence::kGuessed ? 1u : 0u;
  }
  CHECK(guessed == 19);
  CHECK(std::string(info_text(boards::kBench, 2, 10203).text).rfind("hmc-board:bench;protocol:2;firmware:10203;guessed:PA05,", 0) == 0);
}

TEST_CASE("docs/firmware.md's pin map is the seed variant's table") {
  std::ifstream in(HMC_FIRMWARE_DOC);
  REQUIRE(in);
  const std::string doc((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (uint32_t i = 0; i < boards::kSeed.count; ++i) {
    const PinAssignment& a = boards::kSeed.pins[i];
    // "| PA15 | strip1 | C: SERCOM2 PAD3 | inferred |"
    std::string function = "GPIO";
    if (a.function != 0) {
      const char* unit = a.unit == Unit::kEic ? "EXTINT" : a.unit == Unit::kSercom ? "SERCOM"
                         : a.unit == Unit::kTc                                  ? "TC"
                                                                                : "TCC";
      function = std::string(1, a.function) + ": " + unit;
      if (a.unit == Unit::kEic) {
        function += std::to_string(a.index);
      } else {
        function += std::to_string(a.instance) + (a.unit == Unit::kSercom ? " PAD" : " WO[") +
                    std::to_string(a.index) + (a.unit == Unit::kSercom ? "" : "]");
      }
    }
    const std::string row = "| " + pin_text(a.pin) + " | " + role_name(a.role) + " | " + function + " | " +
                            evidence_name(a.evidence) + " |";
    INFO(row);
    CHECK(doc.find(row) != std::string::npos);
  }
}
