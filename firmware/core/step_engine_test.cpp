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

// Lane i's steps since power-up (derived from its counters, as the main loop reads them).
uint32_t total(const StepEngine& e, uint8_t i) {
  return hmc::fw::step_engine_detail::lane_steps(e.lanes[i], e.lanes[i].next).total;
}

// A clock in ticks: each port call costs kCallTicks, waits move it to their end.
// As on the SAMD21, the armed compare raises STEP by itself (at its time) and the interrupt only
// sets the pulse's end.
template <uint32_t Reach>
struct ClockPortOf {
  static constexpr uint8_t kLane = 0;
  static constexpr uint32_t kReachTicks = Reach;
  static constexpr uint32_t kCostTicks = 192;
  static constexpr bool kArmedStepsByHardware = true;
  static constexpr uint32_t kCallTicks = 40;
  uint32_t clock = 0;
  uint32_t armed = 0;
  bool armed_steps = false;
  bool entered_by_compare = false;  // entered by the compare arm() set
  bool matches_at_disarm = false;   // the armed compare matches as the interrupt disarms it
  bool matched_at_disarm = false;
  std::vector<uint32_t> rises;  // the time of each STEP rise
  // One letter a port call: F the armed STEP's end, H high, A ack, D disarm, E entry, W wait,
  // M arm.
  std::string calls;

  // The compare's flag: set by the compare that brought the entry, by the armed time once
  // passed, or by a match that comes just as the interrupt disarms it (matches_at_disarm).
  bool event_fired(const StepEngine&) const {
    return entered_by_compare || matched_at_disarm ||
           (armed != 0 && static_cast<int32_t>(clock - armed) >= 0);
  }
  void ack_event() { calls += 'A'; }
  void fired(uint32_t when) {
    calls += 'F';
    rises.push_back(when);  // the hardware raised it at the compare
    clock += kCallTicks;
  }
  void disarm() {
    calls += 'D';
    armed_steps = false;
    matched_at_disarm = matches_at_disarm;
  }
  void park(uint32_t now) {
    calls += 'P';
    armed = now;
  }
  uint32_t take_entry() {
    calls += 'E';
    return clock;
  }
  void step_high(uint32_t) {
    calls += 'H';
    clock += kCallTicks;
    rises.push_back(clock);
  }
  uint32_t stopwatch() { return clock; }
  uint32_t elapsed(uint32_t mark) { return clock - mark; }
  void step_low(uint32_t mark) {
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
  void rearm(uint32_t when) { arm(when, armed_steps); }
  void arm(uint32_t when, bool steps) {
    calls += 'M';
    armed = when;
    armed_steps = steps;
  }
};
using ClockPort = ClockPortOf<hmc::fw::kMaxSegmentTicks>;

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
  lane.pending = 1;
  const std::vector<uint32_t> due = {10000, 10150, 10300, 10450, 10600, 10750,
                                     11710, 12670, 13630, 14590};

  ClockPort port;
  uint32_t now = 10000;
  for (int entries = 0; entries < 10 && port.rises.size() < due.size(); ++entries) {
    port.clock = now;
    port.entered_by_compare = entries > 0;  // the first entry is the main loop's kick (e.pending)
    port.armed = 0;
    hmc::fw::run_lane_interrupt(e, port);
    if (port.armed == 0) break;
    now = port.armed;
  }
  REQUIRE(port.rises.size() == due.size());
  for (size_t i = 0; i < due.size(); ++i) {
    INFO("step " << i << " due at " << due[i] << ", raised at " << port.rises[i]);
    CHECK(port.rises[i] >= due[i]);
    CHECK(port.rises[i] <= due[i] + 2 * ClockPort::kCallTicks);
  }
  CHECK(total(e, 0) == due.size());
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
  lane.pending = 1;

  ClockPort port;
  uint32_t now = 10000;
  std::vector<std::string> entries;
  for (int n = 0; n < 10; ++n) {
    port.clock = now;
    port.entered_by_compare = n > 0;
    port.armed = 0;
    port.calls.clear();
    hmc::fw::run_lane_interrupt(e, port);
    entries.push_back(port.calls);
    if (port.armed == 0) break;
    now = port.armed;
  }
  REQUIRE(entries.size() >= 5);
  // The kick: the compare's STEP disarmed, the clock, the compare parked, then STEP by the CPU
  // (due: no wait).
  CHECK(entries[0].rfind("DEPEWH", 0) == 0);
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
  CHECK(total(e, 0) == 8);
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
    hmc::fw::run_lane_interrupt(e, port);
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
  lane.pending = 1;
  ClockPort port;
  const std::vector<uint32_t> armed = play(e, port, 10000, 20);
  REQUIRE(armed.size() >= due.size());
  for (size_t i = 0; i < due.size(); ++i) {
    INFO("step " << i);
    CHECK(armed[i] == due[i]);  // the start's event (no step) at 10 000 armed nothing
  }
  CHECK(total(e, 0) == due.size());
  CHECK(lane.ramp_left == 0);
}

TEST_CASE("step interrupt: a halt inside a ramp segment leaves nothing of it") {
  StepEngine e{};
  hmc::fw::StepLane& lane = e.lanes[0];
  lane.ring[0] = StepSegment{10000, 1, 16, hmc::fw::kSegStart | hmc::fw::kSegNoStep, 0, 0};
  lane.ring[1] = StepSegment{1000u << 16, 64, 0, hmc::fw::kSegRamp, 0, -(1 << 12)};
  lane.tail = 2;
  lane.pending = 1;
  ClockPort port;
  play(e, port, 10000, 4);  // the start and three steps of the segment
  const uint32_t steps = total(e, 0);
  REQUIRE(steps == 3);
  REQUIRE(lane.ramp_left == 60);
  // The main loop halts (as StepScheduler::post_halt does), then starts a plain move.
  lane.halt_upto = lane.tail;
  lane.halt_request = 0x80 | 3;
  lane.pending = 1;
  port.clock += 10;
  port.entered_by_compare = false;
  hmc::fw::run_lane_interrupt(e, port);
  CHECK(port.rises.size() == steps);
  CHECK(lane.ramp_left == 0);
  CHECK(lane.moving == 0);
  lane.ring[2] = StepSegment{50000, 1, 16, hmc::fw::kSegStart | hmc::fw::kSegNoStep, 0, 0};
  lane.ring[3] = StepSegment{700, 2, 0, 0, 0, 0};
  lane.tail = 4;
  lane.pending = 1;
  const std::vector<uint32_t> armed = play(e, port, 50000, 6);
  REQUIRE(armed.size() >= 2);
  CHECK(armed[0] == 50700);
  CHECK(armed[1] == 51400);
  CHECK(total(e, 0) == steps + 2);
}

TEST_CASE("step interrupt: derived counts equal per-step counters mid-segment, at boundaries, "
          "after a halt") {
  // Motor 1 from a start without a step at 10 000: 3 steps 960 apart, a wait, a DIR event,
  // 2 steps 800 apart, a ramp segment of 8 (from 1 000.5 ticks, −1/16 tick a step), 5 steps 700
  // apart; after each entry the lane's derived counts are compared with what counters updated
  // at every step would hold (the steps, the last step's time, the time since the step before,
  // the first one's since the start's anchor). A halt after two of the last run's steps.
  using hmc::fw::kSegDir;
  using hmc::fw::kSegNoStep;
  using hmc::fw::kSegRamp;
  using hmc::fw::kSegStart;
  constexpr uint32_t kAnchor = 10000;
  std::vector<uint32_t> times;  // every step's planned time
  uint32_t t = kAnchor;
  for (int j = 0; j < 3; ++j) times.push_back(t += 960);
  t += 500 + 300;  // the wait and the DIR event
  for (int j = 0; j < 2; ++j) times.push_back(t += 800);
  constexpr uint32_t kD0 = (1000u << 16) + (1u << 15);
  constexpr int32_t kAdd = -(1 << 12);
  uint32_t acc = 0;  // the accumulator's fraction, Q0.16
  for (int j = 0; j < 8; ++j) {
    acc += kD0 + static_cast<uint32_t>(j * kAdd);
    times.push_back(t += acc >> 16);
    acc &= 0xFFFFu;
  }
  for (int j = 0; j < 5; ++j) times.push_back(t += 700);

  StepEngine e{};
  hmc::fw::StepLane& lane = e.lanes[0];
  lane.ring[0] = StepSegment{kAnchor, 1, 16, kSegStart | kSegNoStep, 0, 0};
  lane.ring[1] = StepSegment{960, 3, 0, 0, 0, 0};
  lane.ring[2] = StepSegment{500, 1, 0, kSegNoStep, 0, 0};
  lane.ring[3] = StepSegment{300, 1, 0, kSegDir, 0, 0};
  lane.ring[4] = StepSegment{800, 2, 0, 0, 0, 0};
  lane.ring[5] = StepSegment{kD0, 8, 0, kSegRamp, 0, kAdd};
  lane.ring[6] = StepSegment{700, 5, 0, 0, 0, 0};
  lane.tail = 7;
  lane.pending = 1;

  auto check = [&](size_t steps, bool halted) {
    const hmc::fw::step_engine_detail::LaneSteps s =
        hmc::fw::step_engine_detail::lane_steps(lane, e.lanes[0].next);
    INFO("after " << steps << " steps");
    REQUIRE(s.total == steps);
    if (steps == 0) return;
    CHECK(s.last_step == times[steps - 1]);
    const uint32_t before = steps >= 2 ? times[steps - 2] : kAnchor;
    CHECK(s.last_interval == (halted ? 0 : times[steps - 1] - before));
  };
  ClockPort port;
  uint32_t now = kAnchor;
  for (int n = 0; port.rises.size() < times.size() - 3; ++n) {
    REQUIRE(n < 40);
    port.clock = now;
    port.entered_by_compare = n > 0;
    port.armed = 0;
    hmc::fw::run_lane_interrupt(e, port);
    check(port.rises.size(), false);
    REQUIRE(port.armed != 0);
    now = port.armed;
  }
  CHECK(lane.head == 7);  // every segment taken, the last one playing
  // Halted before the third step of the last run (as StepScheduler::post_halt asks).
  lane.halt_upto = lane.tail;
  lane.halt_request = 0x80 | 3;
  lane.pending = 1;
  port.clock = now - 100;
  port.entered_by_compare = false;
  hmc::fw::run_lane_interrupt(e, port);
  CHECK(port.rises.size() == times.size() - 3);
  check(port.rises.size(), true);
  CHECK(lane.moving == 0);
}

TEST_CASE("step interrupt: a kick after the armed compare counts the step the hardware made") {
  // Motor 1 steps every 960 ticks from 10 000; the main loop asks for a halt at the next step's
  // time. Where the compare matched before the kick was taken (its flag set at entry), the
  // hardware raised STEP: the step is counted before the halt drops the move, and no STEP is
  // raised again (its pulse may be over: that would be a second step). Where it matched as the
  // interrupt disarmed it (the flag set only after the disarm), its STEP may have found the mask
  // 0: counted and raised by the CPU (no second edge if the hardware did raise it). Where the
  // kick came first, the compare raises nothing (disarmed) and the step is not made.
  struct Kick {
    uint32_t at;
    bool matches_at_disarm;
  };
  for (const Kick kick : {Kick{10970, false}, Kick{11300, false}, Kick{10955, true},
                          Kick{10950, false}}) {
    const uint32_t kick_at = kick.at;
    StepEngine e{};
    hmc::fw::StepLane& lane = e.lanes[0];
    lane.ring[0] = StepSegment{10000, 1, 16, hmc::fw::kSegStart, 0, 0};
    lane.ring[1] = StepSegment{960, 1000000, 0, 0, 0, 0};
    lane.tail = 2;
    lane.pending = 1;
    ClockPort port;
    port.clock = 10000;
    hmc::fw::run_lane_interrupt(e, port);
    REQUIRE(port.armed == 10960);
    REQUIRE(port.armed_steps);
    REQUIRE(lane.total == 1);

    lane.halt_upto = lane.tail;
    lane.halt_request = 0x80 | 1;
    lane.pending = 1;
    port.clock = kick_at;
    port.entered_by_compare = false;
    port.matches_at_disarm = kick.matches_at_disarm;
    port.calls.clear();
    hmc::fw::run_lane_interrupt(e, port);
    INFO("kick at " << kick_at << ": " << port.calls);
    CHECK(!port.armed_steps);  // nothing armed after the halt
    CHECK(lane.moving == 0);
    if (kick.matches_at_disarm) {
      CHECK(lane.total == 2);
      // Disarmed first, STEP raised by the CPU at once, the clock, the compare parked there.
      CHECK(port.calls.rfind("DHEP", 0) == 0);
      CHECK(port.armed == kick_at + ClockPort::kCallTicks);
      continue;
    }
    CHECK(port.calls.rfind("DEP", 0) == 0);  // disarmed first, the clock, the compare parked
    CHECK(port.armed == kick_at);           // the compare parked at the kick's clock
    if (kick_at >= 10960) {
      CHECK(lane.total == 2);
      CHECK(port.calls.find('H') == std::string::npos);  // no second step
    } else {
      CHECK(lane.total == 1);
      CHECK(port.calls.find('H') == std::string::npos);
    }
  }
}

TEST_CASE("step interrupt: an event beyond the compare's reach is reached through relays") {
  // A compare that reaches 4 096 ticks (as TCC2's 16-bit counter reaches 2^15): steps 10 000
  // ticks apart arm relays on the way, each stepping nothing, and every step comes at its time.
  using Port = ClockPortOf<4096>;
  StepEngine e{};
  hmc::fw::StepLane& lane = e.lanes[0];
  lane.ring[0] = StepSegment{10000, 1, 16, hmc::fw::kSegStart, 0, 0};
  lane.ring[1] = StepSegment{10000, 3, 0, 0, 0, 0};
  lane.tail = 2;
  lane.pending = 1;
  Port port;
  uint32_t now = 10000;
  std::vector<uint32_t> armed;
  for (int n = 0; n < 40; ++n) {
    port.clock = now;
    port.entered_by_compare = n > 0;
    port.armed = 0;
    hmc::fw::run_lane_interrupt(e, port);
    if (port.armed == 0 || lane.compare == hmc::fw::kCompareIdle) break;
    // Each compare within the reach of the clock at the arm.
    CHECK(port.armed - port.clock <= Port::kReachTicks);
    CHECK(port.armed_steps == (lane.compare == hmc::fw::kCompareEvent));
    armed.push_back(port.armed);
    now = port.armed;
  }
  const std::vector<uint32_t> due = {10000, 20000, 30000, 40000};
  REQUIRE(port.rises.size() == due.size());
  for (size_t i = 0; i < due.size(); ++i) {
    INFO("step " << i);
    CHECK(port.rises[i] >= due[i]);
    CHECK(port.rises[i] <= due[i] + 2 * Port::kCallTicks);
  }
  // Two relays between steps 10 000 apart (a relay at most 4 096 ahead), then the step.
  CHECK(armed.size() == 3 * (2 + 1));
  CHECK(total(e, 0) == due.size());
}
