// Instruction counts of the firmware core on a Cortex-M0 under qemu (scripts/bench qemu).
//
// Method (docs/performance.md, "Cost on the CPU"): qemu runs with -icount shift=10, so every
// guest instruction takes exactly 1024 ns of virtual time, and the microbit's SysTick counts
// the 16 MHz core clock of virtual time: 16.384 ticks per instruction. measure() reads SysTick,
// calls a function, reads SysTick again; the same measurement of an empty function (one `bx lr`)
// is subtracted, so a result is the exact number of instructions the function executed,
// its own return included. A calibration loop of known length checks the arithmetic.
//
// The core (StepScheduler, FrameParser) is compiled exactly as for the board (-Os, M0+); the
// HAL is faked with a register write per call, and what the fakes cost is measured and
// reported on its own.
#include <stdint.h>

#include "firmware/core/controller.h"
#include "firmware/core/frame_parser.h"
#include "firmware/core/step_scheduler.h"
#include "semihost.h"

using hmc::fw::FrameParser;
using hmc::fw::MoveSpec;
using hmc::fw::StepScheduler;
using hmc::fw::StepStatus;
using hmc::hal::Ticks;

namespace {

// ---- measuring --------------------------------------------------------------------------------

using Fn = void (*)(void*, uint32_t);

volatile uint32_t* const kSysTickCsr = reinterpret_cast<volatile uint32_t*>(0xE000E010);
volatile uint32_t* const kSysTickRvr = reinterpret_cast<volatile uint32_t*>(0xE000E014);
volatile uint32_t* const kSysTickCvr = reinterpret_cast<volatile uint32_t*>(0xE000E018);

// 16 MHz SysTick, 1024 ns per instruction: 16.384 = 16384 / 1000 ticks per instruction.
constexpr uint32_t kTicksPerInstrNum = 16384;
constexpr uint32_t kTicksPerInstrDen = 1000;

extern "C" {
// One instruction: the reference every measurement subtracts.
__attribute__((naked, noinline)) void empty_fn(void*, uint32_t) { asm volatile("bx lr"); }
// 2·n + 1 instructions (n ≥ 1): the calibration loop.
__attribute__((naked, noinline)) void spin_fn(void*, uint32_t) {
  asm volatile(
      ".syntax unified\n"
      "1: subs r1, #1\n"
      "   bne 1b\n"
      "   bx lr\n");
}
}

// SysTick ticks (down-counter, 24 bits) across one call of fn(a0, a1).
__attribute__((noinline)) uint32_t measure_ticks(Fn fn, void* a0, uint32_t a1) {
  asm volatile("" ::: "memory");
  const uint32_t before = *kSysTickCvr;
  asm volatile("" ::: "memory");
  fn(a0, a1);
  asm volatile("" ::: "memory");
  const uint32_t after = *kSysTickCvr;
  asm volatile("" ::: "memory");
  return (before - after) & 0xFFFFFFu;
}

// Instructions in a tick count, rounded. SysTick shows floor(phase + 16.384·k) after k
// instructions, so a difference is off by at most one tick (0.06 instruction): rounding is exact.
uint32_t ticks_to_instructions(uint32_t ticks) {
  const uint64_t scaled = uint64_t{ticks} * kTicksPerInstrDen;
  return static_cast<uint32_t>((scaled + kTicksPerInstrNum / 2) / kTicksPerInstrNum);
}

// Instructions of the measuring window itself: the empty measurement minus the empty
// function's one instruction (set by calibrate()).
uint32_t g_window = 0;

// Instructions fn executed, its return included.
uint32_t instructions(Fn fn, void* a0, uint32_t a1) {
  return ticks_to_instructions(measure_ticks(fn, a0, a1)) - g_window;
}

// ---- output -----------------------------------------------------------------------------------

char g_line[320];
uint32_t g_len = 0;

void put(const char* s) {
  while (*s != 0 && g_len + 1 < sizeof g_line) g_line[g_len++] = *s++;
}
void put_u(uint64_t v) {
  char digits[24];
  int n = 0;
  do {
    digits[n++] = static_cast<char>('0' + v % 10);
    v /= 10;
  } while (v != 0);
  char out[24];
  for (int i = 0; i < n; ++i) out[i] = digits[n - 1 - i];
  out[n] = 0;
  put(out);
}
// v / den with one decimal, rounded.
void put_ratio(uint64_t v, uint64_t den) {
  const uint64_t tenths = (v * 10 + den / 2) / den;
  put_u(tenths / 10);
  char frac[3] = {'.', static_cast<char>('0' + tenths % 10), 0};
  put(frac);
}
void flush() {
  g_line[g_len] = 0;
  semihost_write(g_line);
  g_len = 0;
}
void line(const char* s) {
  put(s);
  put("\n");
  flush();
}

bool g_ok = true;
void fail(const char* what) {
  put("bench: FAILED: ");
  put(what);
  put("\n");
  flush();
  g_ok = false;
}

// ---- statistics -------------------------------------------------------------------------------

// Per interrupt: instructions.
constexpr uint32_t kMaxSamples = 1600;
constexpr uint32_t kMaxSteps = 65536;  // interrupts a scenario may take
uint16_t g_samples[kMaxSamples];

void sort(uint16_t* a, uint32_t n) {  // shell sort: small and good enough for 1 600 samples
  for (uint32_t gap = n / 2; gap > 0; gap /= 2) {
    for (uint32_t i = gap; i < n; ++i) {
      const uint16_t v = a[i];
      uint32_t j = i;
      for (; j >= gap && a[j - gap] > v; j -= gap) a[j] = a[j - gap];
      a[j] = v;
    }
  }
}

struct Stats {
  uint32_t count = 0;
  uint64_t total = 0;
  uint32_t median = 0;
  uint32_t p99 = 0;
  uint32_t max = 0;
};

Stats stats_of(uint16_t* a, uint32_t n) {
  Stats s;
  s.count = n;
  for (uint32_t i = 0; i < n; ++i) s.total += a[i];
  if (n == 0) return s;
  sort(a, n);
  s.median = a[n / 2];
  s.p99 = a[(n * 99) / 100];
  s.max = a[n - 1];
  return s;
}

// ---- fake HAL and port ------------------------------------------------------------------------

// The main loop's HAL (StepScheduler::fill, start) on plain variables, and each lane's step
// interrupt port doing what the SAMD21's (firmware/targets/samd21/step_fast_path.h) does in one
// register access per call, on volatile variables: the pulse's end one store, the DMA's mask one
// store, a CPU-raised STEP two stores, SysTick one load, the compare one store (the chip's
// write also waits for synchronisation), DIR one store. The pulses themselves are the DMA's.
constexpr uint32_t kBenchCostTicks = 48;  // as Samd21StepPort::kCostTicks
volatile uint32_t g_port = 0;     // OUTSET
volatile uint32_t g_dir = 0;
volatile uint32_t g_systick = 0;  // SysTick at the interrupt's entry
volatile uint32_t g_wait_clock = 0u - 0x800000u;  // SysTick after a wait: far on
// Per lane (motor − 1):
volatile uint32_t g_compare[3];   // CC0
volatile uint32_t g_compare1[3];  // CC1: the pulse's end (the DMA lowers STEP there)
volatile uint32_t g_set_mask[3];  // what CC0's DMA raises
volatile uint32_t g_fired = 0;    // the interrupt is entered by the compare arm() set
volatile uint32_t g_flags = 0;    // INTFLAG

class FakeTimer final : public hmc::hal::StepTimer {
 public:
  Ticks now() const override { return clock; }
  void schedule(Ticks when) override { due = when; }
  Ticks clock = 0;
  Ticks due = ~Ticks{0};
};

class FakePins final : public hmc::hal::StepPins {
 public:
  void set_dir(uint8_t motor, bool reverse) override { g_dir = (uint32_t{motor} << 1) | reverse; }
  void set_step(uint8_t motor, bool high) override { g_port = (uint32_t{motor} << 1) | high; }
};

template <uint8_t Lane>
class BenchPort {
 public:
  static constexpr uint8_t kLane = Lane;
  static constexpr uint32_t kCostTicks = kBenchCostTicks;
  static constexpr uint32_t kReachTicks = hmc::fw::kMaxSegmentTicks;
  static constexpr bool kArmedStepsByHardware = true;
  explicit BenchPort(uint32_t now) : now_(now) {}
  bool event_fired(const hmc::fw::StepEngine&) { return g_fired != 0; }  // INTFLAG's load
  void ack_event() { g_flags = 1; }
  void fired(uint32_t) {}  // the DMA raised STEP and set its end
  void disarm() { g_set_mask[Lane] = 0; }
  void park(uint32_t now) { g_compare[Lane] = now; }
  uint32_t take_entry() {
    g_flags = 3;
    return now_;
  }
  void step_high(uint32_t near) {  // CC1 from the clock, then OUTSET
    g_compare1[Lane] = near + ((g_systick - near) & 0xFFFFFFu) + hmc::fw::kStepHighTicks;
    g_port = Lane;
  }
  uint32_t stopwatch() { return g_systick; }
  uint32_t elapsed(uint32_t mark) { return (mark - g_systick) & 0xFFFFFFu; }
  void step_low(uint32_t) {}  // the DMA ends the pulse
  void set_dir(uint8_t index, bool reverse) { g_dir = (uint32_t{index} << 1) | reverse; }
  // Time since entry on the fake SysTick (which says any wait is over at once): the SAMD21's
  // port reads a SysTick-based clock instead, one load more.
  int32_t ticks_until(uint32_t when, uint32_t entry, uint32_t mark) {
    return static_cast<int32_t>(when - entry) - static_cast<int32_t>(elapsed(mark));
  }
  void wait_until(uint32_t when, uint32_t entry, uint32_t mark) {
    const int32_t ahead = static_cast<int32_t>(when - entry);
    while (ahead - static_cast<int32_t>((mark - g_wait_clock) & 0xFFFFFFu) > 0) {
    }
  }
  void arm(uint32_t when, bool step) {
    g_set_mask[Lane] = step ? 1u << Lane : 0;
    g_compare1[Lane] = when + hmc::fw::kStepHighTicks;
    g_compare[Lane] = when;
  }
  void rearm(uint32_t when) {
    g_compare1[Lane] = when + hmc::fw::kStepHighTicks;
    g_compare[Lane] = when;
  }

 private:
  uint32_t now_;
};

// A lane's interrupt as the SAMD21 runs it (run_step_express, then run_step_general): entered
// by its armed compare (the bench sets g_fired) or by the main loop's kick (the counter's value:
// `now`).
template <uint8_t Lane>
__attribute__((noinline)) void step_isr(void* engine, uint32_t now) {
  BenchPort<Lane> port(now);
  hmc::fw::run_lane_interrupt(*static_cast<hmc::fw::StepEngine*>(engine), port);
}

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpmf-conversions"
// The code a member function runs, as a plain function (GCC's bound-member extraction).
Fn fill_fn() { return (Fn)(&StepScheduler::fill); }
Fn feed_fn() { return (Fn)(&FrameParser::feed); }
#pragma GCC diagnostic pop

// ---- the main loop: the link watchdog's cost in Controller::poll ------------------------------

class NoSpi final : public hmc::hal::SpiBus {
 public:
  uint16_t transfer16(uint8_t, uint16_t) override { return 0; }
};
class NoServos final : public hmc::hal::ServoPwm {
 public:
  void set_pulse(uint8_t, uint16_t) override {}
  void release(uint8_t) override {}
};
class NoLeds final : public hmc::hal::LedStrips {
 public:
  void set_color(uint8_t, uint8_t, uint8_t, uint8_t, uint8_t) override {}
};
class OpenSwitches final : public hmc::hal::Switches {
 public:
  bool limit_pressed(uint8_t, uint8_t) const override { return false; }
  bool emergency_pressed() const override { return false; }
};
class NoBuzzer final : public hmc::hal::Buzzer {
 public:
  void tone(uint16_t, uint16_t) override {}
};
class NoBootLeds final : public hmc::hal::BootLeds {
 public:
  void set(bool, bool) override {}
};
// Bytes queued by the benchmark, replies dropped.
class QueueSerial final : public hmc::hal::SerialPort {
 public:
  int read_byte() override { return at < length ? static_cast<uint8_t>(bytes[at++]) : -1; }
  void write(const uint8_t*, uint32_t) override {}
  void queue(const char* text) {
    length = at = 0;
    while (text[length] != 0 && length < sizeof bytes) bytes[length] = text[length], ++length;
  }
  char bytes[64] = {};
  uint32_t length = 0, at = 0;
};

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpmf-conversions"
Fn poll_fn() { return (Fn)(&hmc::fw::Controller::poll); }
#pragma GCC diagnostic pop

// ---- step engine scenarios --------------------------------------------------------------------

struct Scenario {
  const char* name;
  uint8_t motors;
  uint32_t steps[3];
  uint32_t interval[3];
  uint32_t accel;
  uint32_t fill_every;  // ticks between fill() calls; 0: after every interrupt
};

struct Result {
  uint32_t interrupts = 0;
  uint32_t steps = 0;
  uint64_t isr_total = 0;
  uint64_t fill_total = 0;
  uint32_t fills = 0;
  uint64_t ticks = 0;  // from the start to the last event
  bool ok = true;
};

uint16_t g_fill[kMaxSamples];

// Starts the scenario's moves at tick 1000 and plays every interrupt until all motors rest,
// measuring each interrupt and the main loop's fill() after it (the main loop at its busiest:
// once per interrupt), or after the first interrupt at least `fill_every` ticks after the last
// fill (a main loop going round at that period). Medians and maxima are over the first
// kMaxSamples interrupts, the means over all.
Result play(const Scenario& sc) {
  Result r;
  FakeTimer timer;
  FakePins pins;
  StepScheduler sched(timer, pins, StepScheduler::kDefaultHandoverLead);
  timer.clock = 1000;
  for (uint8_t m = 0; m < sc.motors; ++m) {
    const MoveSpec spec{false, 16, sc.steps[m], sc.interval[m], sc.accel};
    if (sched.start(static_cast<uint8_t>(m + 1), spec) != StepStatus::kOk) r.ok = false;
  }
  const Fn fill = fill_fn();
  Ticks filled_at = 0;
  uint32_t fills = 0;
  const Fn isr[3] = {step_isr<0>, step_isr<1>, step_isr<2>};
  for (;;) {
    // The main loop's kick enters every lane's interrupt (as the board pends all three); else
    // the lane whose armed compare comes first.
    Ticks at = ~Ticks{0};
    uint8_t first = 0, last = 3;
    if (timer.due != ~Ticks{0}) {
      at = timer.due;
      g_fired = 0;
    } else {
      int64_t soonest = INT64_MAX;
      for (uint8_t i = 0; i < 3; ++i) {
        if (sched.engine().lanes[i].compare == hmc::fw::kCompareIdle) continue;
        const int32_t d = static_cast<int32_t>(g_compare[i] - static_cast<uint32_t>(timer.clock));
        if (d < soonest) {
          soonest = d;
          first = i;
        }
      }
      if (soonest == INT64_MAX) break;
      at = static_cast<Ticks>(static_cast<int64_t>(timer.clock) + soonest);
      last = static_cast<uint8_t>(first + 1);
      g_fired = 1;
    }
    timer.due = ~Ticks{0};
    if (at > timer.clock) timer.clock = at;
    uint32_t n = 0;
    for (uint8_t i = first; i < last; ++i) {
      if (r.interrupts >= kMaxSteps) break;
      n = instructions(isr[i], &sched.engine(), static_cast<uint32_t>(timer.clock));
      if (r.interrupts < kMaxSamples) {
        g_samples[r.interrupts] = static_cast<uint16_t>(n > 0xFFFF ? 0xFFFF : n);
      }
      r.isr_total += n;
      ++r.interrupts;
    }
    if (r.interrupts >= kMaxSteps) {
      r.ok = false;
      break;
    }
    uint32_t f = 0;
    if (sc.fill_every == 0 || timer.clock - filled_at >= sc.fill_every) {
      f = instructions(fill, &sched, 0);
      filled_at = timer.clock;
      if (fills < kMaxSamples) g_fill[fills] = static_cast<uint16_t>(f > 0xFFFF ? 0xFFFF : f);
      ++fills;
    }
    r.fill_total += f;
  }
  r.fills = fills;
  r.ticks = timer.clock - 1000;
  for (uint8_t m = 1; m <= sc.motors; ++m) {
    if (sched.is_running(m) || sched.steps_done(m) != sc.steps[m - 1]) r.ok = false;
    r.steps += sched.steps_done(m);
  }
  if (sched.clamped_edges() != 0 || sched.starved_events() != 0) r.ok = false;
  return r;
}

// The main loop's share of the scenarios whose fill() runs at a period: fill per 1 000 ticks of
// their step time (in cycles at 48 MHz: tenths of a percent of the CPU).
struct Share {
  const char* name;
  uint64_t fill_total;
  uint64_t ticks;
};
Share g_shares[2];
uint32_t g_share_count = 0;

void run_scenario(const Scenario& sc) {
  const Result r = play(sc);
  if (!r.ok) {
    fail(sc.name);
    return;
  }
  if (sc.fill_every != 0 && g_share_count < 2) {
    g_shares[g_share_count++] = {sc.name, r.fill_total, r.ticks};
  }
  const Stats isr = stats_of(g_samples, r.interrupts < kMaxSamples ? r.interrupts : kMaxSamples);
  const Stats fill = stats_of(g_fill, r.fills < kMaxSamples ? r.fills : kMaxSamples);
  // | scenario | steps | interrupts | per interrupt median / p99 / max | per step (mean) |
  // main loop fill per call median / p99 / max | fill per step (mean) |
  put("| ");
  put(sc.name);
  put(" | ");
  put_u(r.steps);
  put(" | ");
  put_u(r.interrupts);
  put(" | ");
  put_u(isr.median);
  put(" / ");
  put_u(isr.p99);
  put(" / ");
  put_u(isr.max);
  put(" | ");
  put_ratio(r.isr_total, r.steps);
  put(" | ");
  put_u(fill.median);
  put(" / ");
  put_u(fill.p99);
  put(" / ");
  put_u(fill.max);
  put(" | ");
  put_ratio(r.fill_total, r.steps);
  put(" |");
  flush();
  put("\n");
  flush();
}

// ---- parser -----------------------------------------------------------------------------------

void run_parser() {
  static const char* const kFrames[] = {
      "STX#6#STM#1#1#128#1000#500#94#ETX\n",
  };
  for (const char* frame : kFrames) {
    FrameParser parser;
    uint32_t length = 0;
    while (frame[length] != 0) ++length;
    // Check the frame is accepted (plain calls), then measure a fresh parser byte by byte.
    bool judged = false;
    for (uint32_t i = 0; i < length; ++i) judged = parser.feed(static_cast<uint8_t>(frame[i]));
    if (!judged || parser.verdict().reason != hmc::proto::Reason::kOk) {
      fail("the benchmark frame is refused");
      return;
    }
    uint64_t body = 0;
    uint32_t body_max = 0, end = 0;
    const Fn fn = feed_fn();
    for (uint32_t i = 0; i < length; ++i) {
      const uint32_t n = instructions(fn, &parser, static_cast<uint8_t>(frame[i]));
      if (i + 1 < length) {
        body += n;
        if (n > body_max) body_max = n;
      } else {
        end = n;
      }
    }
    if (parser.verdict().reason != hmc::proto::Reason::kOk) fail("measured frame refused");
    put("| `");
    for (uint32_t i = 0; i + 1 < length; ++i) {
      const char c[2] = {frame[i], 0};
      put(c);
    }
    put("\\n` | ");
    put_u(length);
    put(" | ");
    put_ratio(body, length - 1);
    put(" (max ");
    put_u(body_max);
    put(") | ");
    put_u(end);
    put(" | ");
    put_u(body + end);
    put(" | ");
    put_ratio(body + end, length);
    put(" |\n");
    flush();
  }
}

// ---- calibration ------------------------------------------------------------------------------

void calibrate() {
  // The empty measurement, several times: in instructions it must not vary (in ticks it may, by
  // one, with the phase of the 16.384 ticks per instruction).
  uint32_t e[4];
  for (uint32_t& x : e) x = measure_ticks(empty_fn, nullptr, 0);
  const uint32_t empty = ticks_to_instructions(e[0]);
  g_window = empty - 1;
  for (uint32_t x : e) {
    if (ticks_to_instructions(x) != empty) fail("the empty measurement varies");
  }
  line("Calibration: the loop `1: subs r1, #1; bne 1b; bx lr` runs 2n + 1 instructions.");
  line("");
  line("| n | SysTick ticks | measured: round(ticks / 16.384) - window | expected 2n + 1 |");
  line("|---|---|---|---|");
  static const uint32_t kLoops[] = {1, 10, 100, 1000, 10000, 100000};
  for (uint32_t n : kLoops) {
    const uint32_t ticks = measure_ticks(spin_fn, nullptr, n);
    const uint32_t got = instructions(spin_fn, nullptr, n);
    put("| ");
    put_u(n);
    put(" | ");
    put_u(ticks);
    put(" | ");
    put_u(got);
    put(" | ");
    put_u(2 * n + 1);
    put(" |\n");
    flush();
    if (got != 2 * n + 1) fail("calibration");
  }
  put("\nEmpty measurement: ");
  put_u(e[0]);
  put(" ticks = ");
  put_u(empty);
  put(" instructions, of which the window (subtracted from every figure) is ");
  put_u(g_window);
  put(" and the empty function's bx lr 1.\n\n");
  flush();
}

// Controller::poll with the link watchdog off and armed (500 ms, not due): an idle poll, and a
// poll that receives one blank line (the host's keep-alive). The difference is the watchdog's.
void run_main_loop() {
  FakeTimer timer;
  FakePins pins;
  NoSpi spi;
  NoServos servos;
  NoLeds leds;
  OpenSwitches switches;
  NoBuzzer buzzer;
  NoBootLeds boot_leds;
  QueueSerial serial;
  const hmc::fw::Board board{timer, pins, spi, servos, leds, switches, buzzer, boot_leds, serial};
  hmc::fw::ControllerOptions options;
  options.self_test = false;
  hmc::fw::Controller controller(board, options);  // on the stack: no exit-time destructor
  controller.boot(hmc::fw::ResetReport{});
  timer.clock = 48000000;  // 1 s: the boot's timers are past, the next are a second away
  serial.queue("");
  controller.poll();
  const Fn fn = poll_fn();
  uint32_t figures[2][2];  // [off, armed][idle, keep-alive]
  for (int armed = 0; armed < 2; ++armed) {
    serial.queue(armed ? "STX#2#WDG#500#244#ETX\n" : "STX#2#WDG#0#0#ETX\n");
    controller.poll();
    if (controller.watchdog_ms() != (armed ? 500u : 0u)) fail("WDG was not applied");
    serial.queue("");
    figures[armed][0] = instructions(fn, &controller, 0);
    serial.queue("\n");
    figures[armed][1] = instructions(fn, &controller, 0);
  }
  line("");
  line("Controller::poll (the main loop, idle board), instructions per call, link watchdog off and armed:");
  line("");
  line("| poll | watchdog off | armed (500 ms) | the watchdog's share |");
  line("|---|---|---|---|");
  static const char* const kRows[] = {"no byte", "one blank line (keep-alive)"};
  for (int row = 0; row < 2; ++row) {
    put("| ");
    put(kRows[row]);
    put(" | ");
    put_u(figures[0][row]);
    put(" | ");
    put_u(figures[1][row]);
    put(" | ");
    put_u(figures[1][row] - figures[0][row]);
    put(" |\n");
  }
  flush();
}

}  // namespace

int main() {
  *kSysTickRvr = 0xFFFFFF;
  *kSysTickCvr = 0;
  *kSysTickCsr = 0x5;  // enable, processor clock, no interrupt

  calibrate();

  line("The step interrupt (run_lane_interrupt with a port of one register access per call, "
       "as the SAMD21's) and the main loop's StepScheduler::fill after each interrupt, "
       "instructions per call:");
  line("");
  line("| scenario | steps | interrupts | interrupt median / p99 / max | interrupt per step (mean) | "
       "fill median / p99 / max | fill per step (mean) |");
  line("|---|---|---|---|---|---|---|");
  // Constant rate: 1/16 microstep at 10 kHz; three motors on their own grids (100, 130, 177 µs).
  // Ramping: triangles (accelerating then braking the whole move, never cruising). The spec's
  // fastest: three motors at 20 µs (50 000 steps/s each), ramping at 2 000 000 steps/s² (the
  // ramp to 50 000 steps/s would take 625 steps: a triangle), and at constant rate.
  static const Scenario kScenarios[] = {
      {"1 motor, constant rate", 1, {1000, 0, 0}, {4800, 0, 0}, 0, 0},
      {"1 motor, ramping", 1, {1000, 0, 0}, {2400, 0, 0}, 50000, 0},
      {"3 motors, constant rate", 3, {450, 350, 250}, {4800, 6240, 8496}, 0, 0},
      {"3 motors, constant rate, same grid", 3, {450, 450, 450}, {4800, 4800, 4800}, 0, 0},
      {"3 motors, ramping", 3, {450, 350, 250}, {2400, 3120, 4248}, 50000, 0},
      {"3 motors at 20 us, constant rate", 3, {500, 500, 500}, {960, 960, 960}, 0, 0},
      {"3 motors toward 20 us, ramping", 3, {500, 500, 500}, {960, 960, 960}, 2000000, 0},
      // The main loop's share: three motors ramping to the spec's 20 µs and back (1 250-step
      // ramps at 1 000 000 steps/s², 3 500 steps at 50 000 steps/s), fill() every 250 µs.
      {"3 motors to 20 us and back, ramping, fill every 250 us", 3, {6000, 6000, 6000},
       {960, 960, 960}, 1000000, 12000},
      // The same at 200 000 steps/s² (6 250-step ramps, no cruise between).
      {"3 motors to 20 us and back at 200 000 steps/s^2, fill every 250 us", 3,
       {12500, 12500, 12500}, {960, 960, 960}, 200000, 12000},
  };
  for (const Scenario& sc : kScenarios) run_scenario(sc);
  line("");
  line("The main loop's share (fill() at its period), per 1 000 ticks of step time:");
  line("");
  line("| scenario | step time (ticks) | fill per 1 000 ticks |");
  line("|---|---|---|");
  for (uint32_t i = 0; i < g_share_count; ++i) {
    put("| ");
    put(g_shares[i].name);
    put(" | ");
    put_u(static_cast<uint32_t>(g_shares[i].ticks));
    put(" | ");
    put_ratio(g_shares[i].fill_total * 1000, g_shares[i].ticks);
    put(" |");
    flush();
    put("\n");
    flush();
  }

  line("");
  line("FrameParser::feed, instructions per call:");
  line("");
  line("| frame | bytes | per byte before the line end (mean) | line end (verdict) | whole "
       "frame | per byte, whole frame |");
  line("|---|---|---|---|---|---|");
  run_parser();

  run_main_loop();

  return g_ok ? 0 : 1;
}
