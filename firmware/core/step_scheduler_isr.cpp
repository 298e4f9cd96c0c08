// StepScheduler::on_step_timer: the step engine (step_engine.h) over the HAL interfaces, for the
// simulator and the tests. One HAL timer stands for the board's three lane compares: each call
// runs the interrupt of every lane whose compare is due or whose request is pending, then asks
// the timer for the earliest compare armed. The simulated interrupt takes no time: the STEP
// pulse's end is handed to StepTimer::wait_until, which the SAMD21 port does as a busy wait on
// its counter. Nothing in this file divides: ctest's step_interrupt_has_no_division builds this
// object for the M0+ and fails if it calls any division (or 64-bit multiply) helper.
#include "step_scheduler.h"

namespace hmc::fw {
namespace {

// When lane i's compare is armed for (it is armed: compare != kCompareIdle).
uint32_t compare_time(const StepEngine& e, uint8_t i) {
  const StepLane& lane = e.lanes[i];
  return lane.compare == kCompareRelay ? lane.relay_at : e.lanes[i].next;
}

template <uint8_t Lane>
class HalStepPort {
 public:
  static constexpr uint8_t kLane = Lane;
  // The host's interrupt costs nothing: it leaves for any event not yet due.
  static constexpr uint32_t kCostTicks = 1;
  // The HAL timer reaches any event: no relays.
  static constexpr uint32_t kReachTicks = kMaxSegmentTicks;
  // STEP rises only when the interrupt raises it (at the armed compare's entry, `fired`).
  static constexpr bool kArmedStepsByHardware = false;

  HalStepPort(hal::StepTimer& timer, hal::StepPins& pins, hal::Ticks now)
      : timer_(timer), pins_(pins), now_(now) {}

  // The compare the lane armed has come (the timer calls at the time asked or later).
  bool event_fired(const StepEngine& e) const {
    return e.lanes[Lane].compare != kCompareIdle &&
           static_cast<int32_t>(static_cast<uint32_t>(now_) - compare_time(e, Lane)) >= 0;
  }
  void ack_event() {}
  // Entered at the armed compare's time: STEP rises now; step_low ends the pulse.
  void fired(uint32_t) { step_high(); }
  void disarm() {}
  void park(uint32_t) {}
  uint32_t take_entry() { return static_cast<uint32_t>(now_); }

  void step_high(uint32_t = 0) { pins_.set_step(Lane + 1, true); }
  uint32_t stopwatch() { return static_cast<uint32_t>(timer_.now()); }
  void step_low(uint32_t mark) {
    timer_.wait_until(widen(mark + kStepHighTicks));
    pins_.set_step(Lane + 1, false);
  }
  void set_dir(uint8_t index, bool reverse) {
    pins_.set_dir(static_cast<uint8_t>(index + 1), reverse);
  }
  // The host's clock is read, so the entry's mark is not needed.
  int32_t ticks_until(uint32_t when, uint32_t, uint32_t) {
    return static_cast<int32_t>(when - static_cast<uint32_t>(timer_.now()));
  }
  void wait_until(uint32_t when, uint32_t, uint32_t) {
    if (ticks_until(when, 0, 0) > 0) timer_.wait_until(widen(when));
  }
  void arm(uint32_t, bool) {}  // the engine keeps the time; on_step_timer asks the timer
  void rearm(uint32_t) {}

 private:
  // The 64-bit time nearest the interrupt's entry with these low 32 bits.
  hal::Ticks widen(uint32_t t) const {
    const int32_t d = static_cast<int32_t>(t - static_cast<uint32_t>(now_));
    return static_cast<hal::Ticks>(static_cast<int64_t>(now_) + d);
  }

  hal::StepTimer& timer_;
  hal::StepPins& pins_;
  hal::Ticks now_;
};

template <uint8_t Lane>
void run_lane(StepEngine& e, hal::StepTimer& timer, hal::StepPins& pins, hal::Ticks now) {
  HalStepPort<Lane> port(timer, pins, now);
  run_lane_interrupt(e, port);
}

}  // namespace

void StepScheduler::on_step_timer() {
  const hal::Ticks now = timer_.now();
  run_lane<0>(engine_, timer_, pins_, now);
  run_lane<1>(engine_, timer_, pins_, now);
  run_lane<2>(engine_, timer_, pins_, now);
  // The earliest compare armed: the next call.
  bool any = false;
  int32_t first = 0;
  for (uint8_t i = 0; i < kMotors; ++i) {
    if (engine_.lanes[i].compare == kCompareIdle) continue;
    const int32_t d = static_cast<int32_t>(compare_time(engine_, i) - static_cast<uint32_t>(now));
    if (!any || d < first) first = d;
    any = true;
  }
  if (any) timer_.schedule(static_cast<hal::Ticks>(static_cast<int64_t>(now) + first));
}

}  // namespace hmc::fw
