// The DMAC on a bare chip (no image): TC4's compare matches trigger self-linked channels that
// write PORT OUTSET/OUTCLR with word beats; the STEP edges the board sees land at the match's
// tick plus the DMA latency, however late the emulator looks at the timer; simultaneous
// triggers are served by priority level; what is not modelled stops the emulator. TCC1 and TCC2
// free-running: their compare flags, interrupt lines and MCx DMA triggers at the match's tick.
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

// The DMAC on, its descriptor and write-back sections in `ram`.
void dmac_on(Chip& chip) {
  chip.bus_write(kDmac + 0x34, kDescriptors, 4);
  chip.bus_write(kDmac + 0x38, kWriteBack, 4);
  chip.bus_write(kDmac + 0x00, 0xF02, 2);  // DMAENABLE, LVLEN0-3
}

// Channel `n` moving one word from `source` to `destination` at each trigger, for ever.
void endless_word_channel(Chip& chip, Ram& ram, unsigned n, unsigned trigger, unsigned level,
                          uint32_t source, uint32_t destination, uint32_t trigact = 2) {
  const uint32_t at = kDescriptors + 16 * n;
  ram.word(at + 0, 1u | (2u << 8) | (1u << 16));  // BTCTRL: VALID, BEATSIZE WORD; BTCNT 1
  ram.word(at + 4, source);
  ram.word(at + 8, destination);
  ram.word(at + 12, at);  // DESCADDR: itself
  chip.bus_write(kDmac + 0x3F, n, 1);
  chip.bus_write(kDmac + 0x44, (trigger << 8) | (level << 5) | (trigact << 22), 4);
  chip.bus_write(kDmac + 0x40, 2, 1);
}

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
    dmac_on(chip);
  }
  void channel(unsigned n, unsigned trigger, unsigned level, uint32_t source, uint32_t destination,
               uint32_t trigact = 2) {
    endless_word_channel(chip, ram, n, trigger, level, source, destination, trigact);
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

// TCC`index` (1 or 2) free-running in NPWM to `per` at 48 MHz (generator 0 after the
// bootloader, prescaler 1), the step pin of motor 2 an output, and the DMAC on.
struct TccBench {
  Chip chip{ChipOptions{}};
  Ram ram;
  uint32_t base;
  uint64_t origin_ps = 0;  // the enable's write: the counter's tick 0
  uint32_t step = 1u << samd21::board::kDrivers[1].step.number;

  TccBench(unsigned index, uint32_t per) : base(0x42002000 + 0x400 * index) {
    chip.set_memory(&ram);
    chip.bus_write(0x40000420, chip.bus_read(0x40000420, 4) | (1u << (8 + index)), 4);  // APBCMASK
    chip.bus_write(0x40000C02, 0x4000 | (index == 2 ? 0x1B : 0x1A), 2);  // CLKCTRL: CLKEN, GEN 0
    chip.bus_write(kPort + 0x08, step, 4);  // DIRSET
    dmac_on(chip);
    tcc(0x3C, 2);    // WAVE: NPWM
    tcc(0x40, per);  // PER
    origin_ps = chip.now_ps();
    tcc(0x00, 2);    // CTRLA: ENABLE, prescaler DIV1
  }
  void tcc(uint32_t offset, uint32_t value) { chip.bus_write(base + offset, value, 4); }
  uint32_t reg(uint32_t offset) { return chip.bus_read(base + offset, 4); }
  uint32_t count() {
    chip.bus_write(base + 0x05, 4u << 5, 1);  // CTRLBSET: CMD READSYNC
    return reg(0x34);
  }
  // The first picosecond of the counter's `tick`, and the CPU brought to `cycles_before` cycles
  // (one cycle: one tick) before it.
  uint64_t tick_ps(uint64_t tick) const { return origin_ps + (tick * 1000000000000ull + 47999999) / 48000000; }
  void run_to(uint64_t tick, uint64_t cycles_before = 0) {
    chip.charge_cycles(chip.cycles_at(tick_ps(tick)) - cycles_before - chip.cycles());
    chip.advance();
  }
  void channel(unsigned n, unsigned trigger, uint32_t source, uint32_t destination) {
    endless_word_channel(chip, ram, n, trigger, 1, source, destination);  // level 1, one beat
  }
  const Board::Axis& axis() { return chip.board().axis(1); }
};

constexpr uint32_t kMc0 = 1u << 16, kMc1 = 1u << 17;

TEST_CASE("TCC1 free-running: CC0 sets INTFLAG.MC0 at its tick, and NVIC line 16 when enabled") {
  TccBench b(1, 0xFFFFFF);
  b.run_to(20000);
  const uint32_t count = b.count();
  CHECK(count >= 20000);
  CHECK(count < 20100);
  b.tcc(0x44, count + 1000);  // CC0
  b.run_to(count + 1000, 1);  // one tick before the match
  CHECK((b.reg(0x2C) & kMc0) == 0);
  b.run_to(count + 1000);
  CHECK((b.reg(0x2C) & (kMc0 | kMc1)) == kMc0);
  CHECK_FALSE(b.chip.irq_line(16));
  b.tcc(0x28, kMc0);  // INTENSET: MC0
  CHECK(b.chip.irq_line(16));
  CHECK_FALSE(b.chip.irq_line(15));
  CHECK_FALSE(b.chip.irq_line(17));
  b.tcc(0x2C, kMc0);  // cleared: the line falls; set again one period later
  CHECK_FALSE(b.chip.irq_line(16));
  b.run_to((1u << 24) + count + 1000, 1);
  CHECK_FALSE(b.chip.irq_line(16));
  b.run_to((1u << 24) + count + 1000);
  CHECK(b.chip.irq_line(16));
  CHECK(b.chip.violation_message().empty());
}

TEST_CASE("TCC1 MC0 raises STEP by DMA and copies the pulse's end into CC1, whose MC1 lowers it") {
  TccBench b(1, 0xFFFFFF);
  constexpr uint32_t kEnd = kRam + 0x208;
  b.ram.word(kSetMask, b.step);
  b.ram.word(kClearMask, b.step);
  b.channel(2, 0x13, kSetMask, kPort + 0x18);    // TCC1 MC0 → OUTSET
  b.channel(3, 0x13, kEnd, b.base + 0x48);       // TCC1 MC0 → CC1
  b.channel(4, 0x14, kClearMask, kPort + 0x14);  // TCC1 MC1 → OUTCLR
  b.run_to(20000);
  const uint32_t rise = b.count() + 1000;
  SECTION("the copied end ahead of the count: the pin falls at it") {
    b.ram.word(kEnd, rise + 96);
    b.tcc(0x44, rise);
    b.run_to(rise + 5000);  // both matches passed before the emulator looked
    REQUIRE(b.chip.violation_message().empty());
    CHECK(b.reg(0x48) == rise + 96);
    CHECK(b.axis().steps == 1);
    CHECK(b.axis().pulses.ended == 1);
    CHECK(b.axis().rise_ps >= b.tick_ps(rise) + kLatencyPs - 1);
    CHECK(b.axis().rise_ps <= b.tick_ps(rise) + kLatencyPs + 1);
    CHECK(b.axis().pulses.high_min_ps >= ticks(96) - 1);
    CHECK(b.axis().pulses.high_min_ps <= ticks(96) + 1);
    CHECK((b.chip.port().out(0) & b.step) == 0);
  }
  SECTION("the copied end behind the count when it lands: the pin falls after the wrap") {
    b.ram.word(kEnd, rise);
    b.tcc(0x44, rise);
    b.run_to(rise + 5000);
    REQUIRE(b.chip.violation_message().empty());
    CHECK(b.axis().steps == 1);
    CHECK((b.chip.port().out(0) & b.step) != 0);
    b.run_to((1u << 24) + rise + 5000);
    CHECK(b.axis().pulses.ended == 1);
    CHECK(b.axis().pulses.high_min_ps >= ticks(1u << 24) - 1);
    CHECK(b.axis().pulses.high_min_ps <= ticks(1u << 24) + 1);
  }
}

TEST_CASE("TCC2 is 16 bits: CC0 behind the count matches after the wrap, a CC of 0 at it; masks") {
  TccBench b(2, 0xFFFF);
  CHECK(b.reg(0x40) == 0xFFFF);
  b.run_to(30000);
  // CC1 is 0 (its reset value): the count started at 0 at the enable but did not reach it.
  CHECK((b.reg(0x2C) & kMc1) == 0);
  const uint32_t count = b.count();
  b.tcc(0x44, count - 10);  // behind the count
  b.run_to(1u << 16, 1);
  CHECK((b.reg(0x2C) & (1 | kMc0 | kMc1)) == 0);
  b.run_to(1u << 16);  // the wrap: OVF, and the count 0 equals CC1
  CHECK((b.reg(0x2C) & (1 | kMc0 | kMc1)) == (1 | kMc1));
  b.run_to((1u << 16) + count - 10, 1);
  CHECK((b.reg(0x2C) & kMc0) == 0);
  b.run_to((1u << 16) + count - 10);
  CHECK((b.reg(0x2C) & kMc0) != 0);
  b.run_to(3 * (1u << 16) + 123);
  const uint32_t wrapped = b.count();
  const uint64_t tick = (b.chip.now_ps() - b.origin_ps) * 48000000 / 1000000000000ull;
  CHECK(wrapped == tick % (1u << 16));
  b.tcc(0x48, 0x12345);
  CHECK(b.reg(0x48) == 0x2345);
  CHECK(b.chip.violation_message().empty());
}

TEST_CASE("a CC write after a beat that ran ahead over the wrap: modelled unless it matched in between") {
  // TCC2's CC0 matches 4 ticks before the wrap; the DMAC's beat on it (CC0's end copied into
  // CC1) lands 5 cycles later, after the wrap, and has the timer handle the wrap then. The CPU,
  // a tick after the match, writes CC0 again: for the next period's tick 1000 (as the step
  // interrupt re-arms), which is modelled; or for a tick of the old period still ahead of the
  // CPU, which would have matched before the wrap already handled, and is not.
  TccBench b(2, 0xFFFF);
  constexpr uint32_t kEnd = kRam + 0x208;
  b.ram.word(kEnd, 5000);
  b.channel(2, 0x16, kEnd, b.base + 0x48);  // TCC2 MC0 → CC1
  b.tcc(0x44, 0xFFFC);
  b.run_to(0xFFFD);
  REQUIRE(b.chip.violation_message().empty());
  REQUIRE(b.reg(0x48) == 5000);  // the beat ran
  SECTION("a value for the next period") {
    b.tcc(0x2C, kMc0);
    b.tcc(0x44, 1000);
    CHECK(b.chip.violation_message().empty());
    b.run_to((1u << 16) + 1000, 1);
    CHECK((b.reg(0x2C) & kMc0) == 0);
    b.run_to((1u << 16) + 1000);
    CHECK((b.reg(0x2C) & kMc0) != 0);
  }
  SECTION("a value that would have matched before the wrap") {
    b.tcc(0x44, 0xFFFE);
    CHECK(b.chip.violation_message().find("matches before the timer's last handled event") !=
          std::string::npos);
  }
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
