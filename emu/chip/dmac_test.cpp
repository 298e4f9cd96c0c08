// The DMAC on a bare chip (no image): TC4's compare matches trigger self-linked channels that
// write PORT OUTSET/OUTCLR with word beats; the STEP edges the board sees land at the match's
// tick plus the DMA latency, however late the emulator looks at the timer; simultaneous
// triggers are served by priority level; what is not modelled stops the emulator.
#include <catch2/catch.hpp>

#include <cstring>
#include <vector>

#include "board/board.h"
#include "board/samd21_board_map.h"
#include "chip/chip.h"
#include "chip/port.h"

namespace hmc::emu {
namespace {

constexpr uint32_t kRam = 0x20000000;
constexpr uint32_t kDescriptors = kRam;          // BASEADDR: channel n at + 16n
constexpr uint32_t kWriteBack = kRam + 0x100;    // WRBADDR
constexpr uint32_t kSetMask = kRam + 0x200;
constexpr uint32_t kClearMask = kRam + 0x204;
constexpr uint32_t kTc4 = 0x42003000, kDmac = 0x41004800, kPort = 0x41004400;
// dmac.cpp's kTriggerToWriteCycles (a guess) at the 48 MHz CPU clock.
constexpr uint64_t kLatencyPs = 5 * 1000000000000ull / 48000000;
// `n` ticks of the 48 MHz counter in ps (96 ticks: 2 000 000 ps).
constexpr uint64_t ticks(uint64_t n) { return n * 1000000000000ull / 48000000; }

class Ram : public Memory {
 public:
  std::vector<uint8_t> bytes = std::vector<uint8_t>(0x1000);
  bool read(uint32_t address, void* out, uint32_t count) override {
    if (address < kRam || address + count > kRam + bytes.size()) return false;
    std::memcpy(out, &bytes[address - kRam], count);
    return true;
  }
  bool write(uint32_t address, const void* in, uint32_t count) override {
    if (address < kRam || address + count > kRam + bytes.size()) return false;
    std::memcpy(&bytes[address - kRam], in, count);
    return true;
  }
  void word(uint32_t address, uint32_t value) { write(address, &value, 4); }
};

struct StepBench {
  Chip chip{ChipOptions{}};
  Ram ram;
  uint64_t origin_ps = 0;
  uint32_t step1 = 1u << samd21::board::kDrivers[0].step.number;
  uint32_t step2 = 1u << samd21::board::kDrivers[1].step.number;

  StepBench() {
    static_assert(samd21::board::kDrivers[0].step.group == 0 &&
                      samd21::board::kDrivers[1].step.group == 0,
                  "the bench drives STEP 1 and 2 on PA");
    chip.set_memory(&ram);
    chip.bus_write(0x40000420, chip.bus_read(0x40000420, 4) | (1u << 12), 4);  // PM APBCMASK: TC4
    chip.bus_write(0x40000C02, 0x4000 | 0x1C, 2);  // GCLK CLKCTRL: CLKEN, GEN 0, ID TC4_TC5
    chip.bus_write(kPort + 0x08, step1 | step2, 4);  // DIRSET
    chip.bus_write(kTc4 + 0x00, 2u << 2, 2);         // CTRLA: MODE COUNT32
    origin_ps = chip.now_ps();                       // the count starts at the enable's write
    chip.bus_write(kTc4 + 0x00, (2u << 2) | 2u, 2);  // ENABLE
    ram.word(kSetMask, step1);
    ram.word(kClearMask, step1 | step2);
    chip.bus_write(kDmac + 0x34, kDescriptors, 4);
    chip.bus_write(kDmac + 0x38, kWriteBack, 4);
    chip.bus_write(kDmac + 0x00, 0xF02, 2);  // DMAENABLE, LVLEN0-3
  }
  // A channel moving one word from `source` to `destination` at each trigger, for ever.
  void channel(unsigned n, unsigned trigger, unsigned level, uint32_t source, uint32_t destination,
               uint32_t trigact = 2) {
    const uint32_t at = kDescriptors + 16 * n;
    ram.word(at + 0, 1u | (2u << 8) | (1u << 16));  // BTCTRL: VALID, BEATSIZE WORD; BTCNT 1
    ram.word(at + 4, source);
    ram.word(at + 8, destination);
    ram.word(at + 12, at);  // DESCADDR: itself
    chip.bus_write(kDmac + 0x3F, n, 1);
    chip.bus_write(kDmac + 0x44, (trigger << 8) | (level << 5) | (trigact << 22), 4);
    chip.bus_write(kDmac + 0x40, 2, 1);
  }
  void compares(uint32_t cc0, uint32_t cc1) {
    chip.bus_write(kTc4 + 0x18, cc0, 4);
    chip.bus_write(kTc4 + 0x1C, cc1, 4);
  }
  // Runs to `tick` of the counter in one go (as a long CPU block would), then lets the chip
  // catch up.
  void run_to(uint64_t tick) {
    chip.charge_cycles(chip.cycles_at(origin_ps + ticks(tick)) - chip.cycles());
    chip.advance();
  }
  const Board::Axis& axis(unsigned m) { return chip.board().axis(m); }
  uint64_t since_origin(uint64_t ps) const { return ps - origin_ps; }
};

TEST_CASE("TC4 MC0 and MC1 trigger word beats to PORT OUTSET and OUTCLR at the match's tick") {
  StepBench b;
  b.channel(2, 0x1C, 1, kSetMask, kPort + 0x18);    // TC4 MC0 → OUTSET
  b.channel(3, 0x1D, 1, kClearMask, kPort + 0x14);  // TC4 MC1 → OUTCLR
  b.compares(1000, 1096);
  b.run_to(5000);  // both matches passed before the emulator looked: still stamped exactly
  REQUIRE(b.chip.violation_message().empty());
  CHECK(b.axis(0).steps == 1);
  CHECK(b.axis(1).steps == 0);
  CHECK(b.axis(0).pulses.ended == 1);
  // The counter starts at the enable's whole tick; both edges are 5 cycles (the guess) late.
  const uint64_t rise = b.since_origin(b.axis(0).rise_ps);
  CHECK(rise >= ticks(1000) + kLatencyPs - 1);
  CHECK(rise <= ticks(1000) + kLatencyPs + 1);
  CHECK(b.axis(0).pulses.high_min_ps >= ticks(96) - 1);
  CHECK(b.axis(0).pulses.high_min_ps <= ticks(96) + 1);
  CHECK(b.axis(0).pulses.high_max_ps == b.axis(0).pulses.high_min_ps);
  CHECK((b.chip.port().out(0) & (b.step1 | b.step2)) == 0);

  SECTION("the self-linked descriptors run again at the next matches, with RAM's masks then") {
    b.ram.word(kSetMask, b.step1 | b.step2);
    b.compares(6000, 6096);
    b.run_to(6050);  // in the middle of the pulse: both pins high
    CHECK((b.chip.port().out(0) & (b.step1 | b.step2)) == (b.step1 | b.step2));
    b.run_to(7000);
    CHECK(b.axis(0).steps == 2);
    CHECK(b.axis(1).steps == 1);
    CHECK(b.axis(1).pulses.high_min_ps >= ticks(96) - 1);
    CHECK(b.axis(1).pulses.high_min_ps <= ticks(96) + 1);
    CHECK(b.axis(0).pulses.low_min_ps + b.axis(0).pulses.high_min_ps ==
          b.axis(0).pulses.period_min_ps);
    CHECK(b.axis(0).pulses.period_min_ps >= ticks(5000) - 1);
    CHECK(b.axis(0).pulses.period_min_ps <= ticks(5000) + 1);
  }
  SECTION("a zero mask raises nothing: the counter may match again with nothing armed") {
    b.ram.word(kSetMask, 0);
    b.compares(6000, 6096);
    b.run_to(7000);
    CHECK(b.axis(0).steps == 1);
  }
  SECTION("a CPU write to PORT first lets the beats due before it land") {
    b.compares(6000, 6096);
    b.chip.charge_cycles(b.chip.cycles_at(b.origin_ps + ticks(6200)) - b.chip.cycles());
    b.chip.bus_write(0x60000000 + 0x18, b.step2, 4);  // IOBUS OUTSET, no chip.advance() before it
    CHECK(b.axis(0).steps == 2);
    CHECK((b.chip.port().out(0) & b.step1) == 0);  // raised at 6000, cleared at 6096
    CHECK((b.chip.port().out(0) & b.step2) != 0);
  }
}

TEST_CASE("triggers at one tick are served by channel priority level") {
  StepBench b;
  SECTION("the clear channel on the higher level: cleared first, then set (the pin stays high)") {
    b.channel(2, 0x1C, 1, kSetMask, kPort + 0x18);
    b.channel(3, 0x1D, 2, kClearMask, kPort + 0x14);
    b.compares(1000, 1000);
    b.run_to(2000);
    CHECK((b.chip.port().out(0) & b.step1) != 0);
    CHECK(b.axis(0).pulses.ended == 0);
  }
  SECTION("the same level: the lower channel number (set) first, then the clear") {
    b.channel(2, 0x1C, 1, kSetMask, kPort + 0x18);
    b.channel(3, 0x1D, 1, kClearMask, kPort + 0x14);
    b.compares(1000, 1000);
    b.run_to(2000);
    CHECK((b.chip.port().out(0) & b.step1) == 0);
    CHECK(b.axis(0).pulses.ended == 1);
    CHECK(b.axis(0).pulses.high_min_ps == 0);
  }
}

TEST_CASE("a beat that writes the next compare chains a second match, stamped at its own tick") {
  // The step engine's chain (step_pulses.h): the match raises STEP, ends it at CC1, and writes
  // the next compare from RAM; the next match does the same. The emulator looks at the timer
  // only after both matches, as after a long CPU block: each edge still lands at its own tick.
  StepBench b;
  constexpr uint32_t kNextCompare = kRam + 0x208, kEnd = kRam + 0x20C;
  b.ram.word(kNextCompare, 1300);
  b.ram.word(kEnd, 1096);
  b.channel(2, 0x1C, 1, kSetMask, kPort + 0x18);    // MC0 → OUTSET
  b.channel(3, 0x1D, 1, kClearMask, kPort + 0x14);  // MC1 → OUTCLR
  b.channel(4, 0x1C, 1, kEnd, kTc4 + 0x1C);         // MC0 → CC1 (the pulse's end)
  b.channel(5, 0x1C, 1, kNextCompare, kTc4 + 0x18); // MC0 → CC0 (the next match)
  b.compares(1000, 0xFFFFFFFF);
  b.run_to(1150);  // the first pulse over: the next compare is 1300, its end still 1096
  b.ram.word(kEnd, 1396);
  b.run_to(5000);
  REQUIRE(b.chip.violation_message().empty());
  CHECK(b.axis(0).steps == 2);
  CHECK(b.axis(0).pulses.ended == 2);
  const uint64_t rise = b.since_origin(b.axis(0).rise_ps);
  CHECK(rise >= ticks(1300) + kLatencyPs - 1);
  CHECK(rise <= ticks(1300) + kLatencyPs + 1);
  CHECK(b.axis(0).pulses.high_max_ps <= ticks(96) + 1);
  CHECK(b.axis(0).pulses.period_max_ps <= ticks(300) + 1);
}

TEST_CASE("what the DMAC model does not cover stops the emulator, naming it") {
  StepBench b;
  SECTION("a trigger action other than one beat") {
    b.channel(2, 0x1C, 1, kSetMask, kPort + 0x18, 0);
    CHECK(b.chip.violation_message().find("TRIGACT") != std::string::npos);
  }
  SECTION("a trigger source not modelled (TC4 OVF)") {
    b.channel(2, 0x1B, 1, kSetMask, kPort + 0x18);
    CHECK(b.chip.violation_message().find("trigger 27 is not modelled") != std::string::npos);
  }
  SECTION("a channel on a level CTRL leaves off") {
    b.chip.bus_write(kDmac + 0x00, 0, 2);
    b.chip.bus_write(kDmac + 0x00, 0x102, 2);  // level 0 only
    b.channel(2, 0x1C, 1, kSetMask, kPort + 0x18);
    CHECK(b.chip.violation_message().find("LVLEN") != std::string::npos);
  }
}

}  // namespace
}  // namespace hmc::emu
