// The step interrupt (step_engine.h) against a port whose clock moves as the interrupt spends
// time, as the SAMD21's does: events closer than the interrupt's own cost are waited for inside
// it, and no step may come before its time however many passes one entry makes; an entry by
// the compare (whose STEP the hardware raised) sets the pulse's end before any other port call,
// an entry that waited inside clears the old compare's flag with the new compare (else the next
// entry would come in early), and a kick disarms the compare's STEP first and counts a step the
// hardware already made.
#include "step_engine.h"

#include <catch2/catch.hpp>

#include <string>
#include <vector>

namespace {

using hmc::fw::StepEngine;
using hmc::fw::StepSegment;

// A clock in ticks: each port call costs kCallTicks, waits move it to their end.
// As on the SAMD21, the armed compare raises STEP by itself (at its time) and the interrupt only
// sets the pulse's end.
struct ClockPort {
  static constexpr uint32_t kCostTicks = 192;
  static constexpr bool kArmedStepsByHardware = true;
  static constexpr uint32_t kCallTicks = 40;
  uint32_t clock = 0;
  uint32_t armed = 0;
  uint8_t armed_steps = 0;
  bool entered_by_compare = false;  // entered by the compare arm() set
  std::vector<uint32_t> rises;  // the time of each STEP rise
  // One letter a port call: F the armed STEP's end, H high, A ack, D disarm, E entry, W wait,
  // M arm.
  std::string calls;

  bool event_fired(const StepEngine&) const { return entered_by_compare; }
  void ack_event() { calls += 'A'; }
  void fired(uint8_t, uint32_t when) {
    calls += 'F';
    rises.push_back(when);  // the hardware raised it at the compare
    clock += kCallTicks;
  }
  void disarm() {
    calls += 'D';
    armed_steps = 0;
  }
  void park(uint32_t now) {
    calls += 'P';
    armed = now;
  }
  uint32_t take_entry() {
    calls += 'E';
    return clock;
  }
  void step_high(uint8_t, uint32_t) {
    calls += 'H';
    clock += kCallTicks;
    rises.push_back(clock);
  }
  uint32_t stopwatch() { return clock; }
  uint32_t elapsed(uint32_t mark) { return clock - mark; }
  void step_low(uint8_t, uint32_t mark) {
    if (clock - mark < hmc::fw::kStepHighTicks) clock = mark + hmc::fw::kStepHighTicks;
  }
  void set_dir(uint8_t, bool) { clock += kCallTicks; }
  int32_t ticks_until(uint32_t when, uint32_t, uint32_t) {
    return static_cast<int32_t>(when - clock);
  }
  void wait_until(uint32_t when, uint32_t, uint32_t) {
    calls += 'W';
    if (ticks_until(when, 0, 0) > 0) clock = when;
  }
  void arm(uint32_t when, uint8_t steps) {
    calls += 'M';
    armed = when;
    armed_steps = steps;
  }
};

}  // namespace

TEST_CASE("step interrupt: events waited for inside one entry come at their time, not before") {
  // Motor 1: a step at 10 000, then five 150 ticks apart (closer than the interrupt's cost:
  // waited for inside; a pass takes 136), then steps 960 ticks apart (the interrupt leaves and comes back).
  StepEngine e{};
  hmc::fw::StepLane& lane = e.lanes[0];
  lane.ring[0] = StepSegment{10000, 1, 16, hmc::fw::kSegStart, 0, 0};
  lane.ring[1] = StepSegment{150, 5, 0, 0, 0, 0};
  lane.ring[2] = StepSegment{960, 4, 0, 0, 0, 0};
  lane.tail = 3;
  e.pending = 1;
  const std::vector<uint32_t> due = {10000, 10150, 10300, 10450, 10600, 10750,
                                     11710, 12670, 13630, 14590};

  ClockPort port;
  uint32_t now = 10000;
  for (int entries = 0; entries < 10 && port.rises.size() < due.size(); ++entries) {
    port.clock = now;
    port.entered_by_compare = entries > 0;  // the first entry is the main loop's kick (e.pending)
    port.armed = 0;
    hmc::fw::run_step_interrupt(e, port);
    if (port.armed == 0) break;
    now = port.armed;
  }
  REQUIRE(port.rises.size() == due.size());
  for (size_t i = 0; i < due.size(); ++i) {
    INFO("step " << i << " due at " << due[i] << ", raised at " << port.rises[i]);
    CHECK(port.rises[i] >= due[i]);
    CHECK(port.rises[i] <= due[i] + 2 * ClockPort::kCallTicks);
  }
  CHECK(lane.total == due.size());
}

TEST_CASE("step interrupt: an entry by its compare sets the pulse's end before anything else") {
  // Motor 1: steps at 10 000 and every 960 ticks after (each entry by the compare), then two
  // 150 ticks apart (waited for inside: the old compare's flag is cleared with the new compare).
  StepEngine e{};
  hmc::fw::StepLane& lane = e.lanes[0];
  lane.ring[0] = StepSegment{10000, 1, 16, hmc::fw::kSegStart, 0, 0};
  lane.ring[1] = StepSegment{960, 3, 0, 0, 0, 0};
  lane.ring[2] = StepSegment{150, 2, 0, 0, 0, 0};
  lane.ring[3] = StepSegment{960, 2, 0, 0, 0, 0};
  lane.tail = 4;
  e.pending = 1;

  ClockPort port;
  uint32_t now = 10000;
  std::vector<std::string> entries;
  for (int n = 0; n < 10; ++n) {
    port.clock = now;
    port.entered_by_compare = n > 0;
    port.armed = 0;
    port.calls.clear();
    hmc::fw::run_step_interrupt(e, port);
    entries.push_back(port.calls);
    if (port.armed == 0) break;
    now = port.armed;
  }
  REQUIRE(entries.size() >= 5);
  // The kick: the compare's STEP disarmed, the clock, then STEP by the CPU.
  CHECK(entries[0].rfind("DEH", 0) == 0);
  for (size_t n = 1; n < entries.size(); ++n) {
    INFO("entry " << n << ": " << entries[n]);
    if (n + 1 < entries.size()) CHECK(entries[n].rfind("FA", 0) == 0);  // the end, then the flag
  }
  // The entry that waited inside (for the steps 150 ticks apart) clears the flag after arming.
  bool waited_and_cleared = false;
  for (const std::string& calls : entries) {
    const size_t wait = calls.find('W');
    if (wait != std::string::npos) waited_and_cleared = calls.find("MA", wait) != std::string::npos;
  }
  CHECK(waited_and_cleared);
  CHECK(lane.total == 8);
}

namespace {

// Steps motor 1 through the ring from the main loop's kick at `start`, each later entry by the
// compare the last one armed: the armed compares (the events' planned times) in order.
std::vector<uint32_t> play(StepEngine& e, ClockPort& port, uint32_t start, int entries) {
  std::vector<uint32_t> armed;
  uint32_t now = start;
  for (int n = 0; n < entries; ++n) {
    port.clock = now;
    port.entered_by_compare = n > 0;
    port.armed = 0;
    hmc::fw::run_step_interrupt(e, port);
    if (port.armed == 0) break;
    armed.push_back(port.armed);
    now = port.armed;
  }
  return armed;
}

}  // namespace

TEST_CASE("step interrupt: ramp segments step on the accumulator's whole ticks, with adds only") {
  // From 10 000 (fraction ½): 4 steps from 1 000.75 ticks falling by 10.25 a step, then 3 more
  // continuing (the main loop's copy of the fraction), then a plain run of 960.
  constexpr int64_t kOne = 65536;
  const int64_t d0 = 1000 * kOne + 3 * kOne / 4;
  const int64_t s = -(10 * kOne + kOne / 4);
  int64_t acc = 10000 * kOne + kOne / 2;
  int64_t d = d0;
  std::vector<uint32_t> due;
  for (int j = 0; j < 7; ++j) {
    acc += d;
    d += s;
    due.push_back(static_cast<uint32_t>(acc / kOne));
  }
  const auto fraction_after_4 = static_cast<uint16_t>([&] {
    int64_t a = kOne / 2;
    for (int j = 0; j < 4; ++j) a += d0 + j * s;
    return a % kOne;
  }());
  for (int j = 1; j <= 3; ++j) due.push_back(due[6] + 960 * static_cast<uint32_t>(j));

  StepEngine e{};
  hmc::fw::StepLane& lane = e.lanes[0];
  lane.ring[0] = StepSegment{10000, 1, 16, hmc::fw::kSegStart | hmc::fw::kSegNoStep, 0, 0};
  lane.ring[1] = StepSegment{static_cast<uint32_t>(d0), 4, static_cast<int16_t>(kOne / 2),
                             hmc::fw::kSegRamp, 0, static_cast<int32_t>(s)};
  lane.ring[2] = StepSegment{static_cast<uint32_t>(d0 + 4 * s), 3,
                             static_cast<int16_t>(fraction_after_4), hmc::fw::kSegRamp, 0,
                             static_cast<int32_t>(s)};
  lane.ring[3] = StepSegment{960, 3, 0, 0, 0, 0};
  lane.tail = 4;
  e.pending = 1;
  ClockPort port;
  const std::vector<uint32_t> armed = play(e, port, 10000, 20);
  REQUIRE(armed.size() >= due.size());
  for (size_t i = 0; i < due.size(); ++i) {
    INFO("step " << i);
    CHECK(armed[i] == due[i]);  // the start's event (no step) at 10 000 armed nothing
  }
  CHECK(lane.total == due.size());
  CHECK(lane.ramp_left == 0);
}

TEST_CASE("step interrupt: a halt inside a ramp segment leaves nothing of it") {
  StepEngine e{};
  hmc::fw::StepLane& lane = e.lanes[0];
  lane.ring[0] = StepSegment{10000, 1, 16, hmc::fw::kSegStart | hmc::fw::kSegNoStep, 0, 0};
  lane.ring[1] = StepSegment{1000u << 16, 64, 0, hmc::fw::kSegRamp, 0, -(1 << 12)};
  lane.tail = 2;
  e.pending = 1;
  ClockPort port;
  play(e, port, 10000, 4);  // the start and three steps of the segment
  const uint32_t steps = lane.total;
  REQUIRE(steps == 3);
  REQUIRE(lane.ramp_left == 60);
  // The main loop halts (as StepScheduler::post_halt does), then starts a plain move.
  lane.halt_upto = lane.tail;
  lane.halt_request = 0x80 | 3;
  e.pending = 1;
  port.clock += 10;
  port.entered_by_compare = false;
  hmc::fw::run_step_interrupt(e, port);
  CHECK(port.rises.size() == steps);
  CHECK(lane.ramp_left == 0);
  CHECK(lane.moving == 0);
  lane.ring[2] = StepSegment{50000, 1, 16, hmc::fw::kSegStart | hmc::fw::kSegNoStep, 0, 0};
  lane.ring[3] = StepSegment{700, 2, 0, 0, 0, 0};
  lane.tail = 4;
  e.pending = 1;
  const std::vector<uint32_t> armed = play(e, port, 50000, 6);
  REQUIRE(armed.size() >= 2);
  CHECK(armed[0] == 50700);
  CHECK(armed[1] == 51400);
  CHECK(lane.total == steps + 2);
}

TEST_CASE("step interrupt: a kick after the armed compare counts the step the hardware made") {
  // Motor 1 steps every 960 ticks from 10 000; the main loop asks for a halt at the next step's
  // time. Where the compare matched before the kick was taken, the hardware raised STEP: the
  // step is counted and its pulse given an end before the halt drops the move. Where the kick
  // came first, the compare raises nothing (disarmed) and the step is not made.
  for (const uint32_t kick_at : {uint32_t{10970}, uint32_t{10950}}) {
    StepEngine e{};
    hmc::fw::StepLane& lane = e.lanes[0];
    lane.ring[0] = StepSegment{10000, 1, 16, hmc::fw::kSegStart, 0, 0};
    lane.ring[1] = StepSegment{960, hmc::fw::kEndlessEvents, 0, 0, 0, 0};
    lane.tail = 2;
    e.pending = 1;
    ClockPort port;
    port.clock = 10000;
    hmc::fw::run_step_interrupt(e, port);
    REQUIRE(port.armed == 10960);
    REQUIRE(port.armed_steps == 1);
    REQUIRE(lane.total == 1);

    lane.halt_upto = lane.tail;
    lane.halt_request = 0x80 | 1;
    e.pending = 1;
    port.clock = kick_at;
    port.calls.clear();
    hmc::fw::run_step_interrupt(e, port);
    INFO("kick at " << kick_at << ": " << port.calls);
    CHECK(port.calls.rfind("DEP", 0) == 0);  // disarmed first, the clock, the compare parked
    CHECK(port.armed_steps == 0);           // nothing armed after the halt
    CHECK(port.armed == kick_at);           // the compare parked at the kick's clock
    CHECK(lane.moving == 0);
    if (kick_at >= 10960) {
      CHECK(lane.total == 2);
      CHECK(port.calls.rfind("DEPH", 0) == 0);  // the pulse's end, from now
    } else {
      CHECK(lane.total == 1);
      CHECK(port.calls.find('H') == std::string::npos);
    }
  }
}
