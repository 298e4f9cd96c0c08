// The step interrupt (step_engine.h) against a port whose clock moves as the interrupt spends
// time, as the SAMD21's does: events closer than the interrupt's own cost are waited for inside
// it, and no step may come before its time however many passes one entry makes.
#include "step_engine.h"

#include <catch2/catch.hpp>

#include <vector>

namespace {

using hmc::fw::StepEngine;
using hmc::fw::StepSegment;

// A clock in ticks: each port call costs kCallTicks, waits move it to their end.
struct ClockPort {
  static constexpr uint32_t kCostTicks = 192;
  static constexpr uint32_t kCallTicks = 40;
  uint32_t clock = 0;
  uint32_t armed = 0;
  bool fired = false;           // entered by the compare arm() set
  std::vector<uint32_t> rises;  // the clock at each STEP rise

  bool event_fired(const StepEngine&) const { return fired; }
  void ack_event() {}
  uint32_t take_entry() { return clock; }
  void step_high(uint8_t) {
    clock += kCallTicks;
    rises.push_back(clock);
  }
  uint32_t stopwatch() { return clock; }
  uint32_t elapsed(uint32_t mark) { return clock - mark; }
  void step_low(uint8_t, uint32_t mark) { wait_for(mark, hmc::fw::kStepHighTicks); }
  void set_dir(uint8_t, bool) { clock += kCallTicks; }
  void wait_for(uint32_t mark, uint32_t ticks) {
    if (clock - mark < ticks) clock = mark + ticks;
  }
  void arm(uint32_t when) { armed = when; }
};

}  // namespace

TEST_CASE("step interrupt: events waited for inside one entry come at their time, not before") {
  // Motor 1: a step at 10 000, then five 150 ticks apart (closer than the interrupt's cost:
  // waited for inside; a pass takes 136), then steps 960 ticks apart (the interrupt leaves and comes back).
  StepEngine e{};
  hmc::fw::StepLane& lane = e.lanes[0];
  lane.ring[0] = StepSegment{10000, 1, 16, hmc::fw::kSegStart, 0};
  lane.ring[1] = StepSegment{150, 5, 0, 0, 0};
  lane.ring[2] = StepSegment{960, 4, 0, 0, 0};
  lane.tail = 3;
  e.pending = 1;
  const std::vector<uint32_t> due = {10000, 10150, 10300, 10450, 10600, 10750,
                                     11710, 12670, 13630, 14590};

  ClockPort port;
  uint32_t now = 10000;
  for (int entries = 0; entries < 10 && port.rises.size() < due.size(); ++entries) {
    port.clock = now;
    port.fired = entries > 0;  // the first entry is the main loop's kick (e.pending)
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
