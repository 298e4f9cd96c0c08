// StepScheduler::on_step_timer: the step engine (step_engine.h) over the HAL interfaces, for the
// simulator and the tests. The simulated interrupt takes no time: the STEP pulse's end is
// handed to StepTimer::wait_until, which the SAMD21 port does as a busy wait on its counter.
// Nothing in this file divides: ctest's step_interrupt_has_no_division builds this object for
// the M0+ and fails if it calls any division (or 64-bit multiply) helper.
#include "step_scheduler.h"

namespace hmc::fw {
namespace {

class HalStepPort {
 public:
  // The host's interrupt costs nothing: it leaves for any event not yet due.
  static constexpr uint32_t kCostTicks = 1;
  // STEP rises only when the interrupt raises it (at the armed compare's entry, `fired`).
  static constexpr bool kArmedStepsByHardware = false;

  HalStepPort(hal::StepTimer& timer, hal::StepPins& pins, hal::Ticks now)
      : timer_(timer), pins_(pins), now_(now) {}

  // The compare the interrupt armed has come (the timer calls at the time asked or later).
  bool event_fired(const StepEngine& e) const {
    return e.next_armed != 0 && static_cast<int32_t>(static_cast<uint32_t>(now_) - e.next_when) >= 0;
  }
  void ack_event() {}
  // Entered at the armed compare's time: STEP rises now; step_low ends the pulse.
  void fired(uint8_t motors, uint32_t) { step_high(motors); }
  void disarm() {}
  void park(uint32_t) {}
  uint32_t take_entry() { return static_cast<uint32_t>(now_); }

  void step_high(uint8_t motors, uint32_t = 0) {
    for (uint8_t i = 0; i < 3; ++i) {
      if ((motors & (1u << i)) != 0) pins_.set_step(static_cast<uint8_t>(i + 1), true);
    }
  }
  uint32_t stopwatch() { return static_cast<uint32_t>(timer_.now()); }
  void step_low(uint8_t motors, uint32_t mark) {
    timer_.wait_until(widen(mark + kStepHighTicks));
    for (uint8_t i = 0; i < 3; ++i) {
      if ((motors & (1u << i)) != 0) pins_.set_step(static_cast<uint8_t>(i + 1), false);
    }
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
  void arm(uint32_t when, uint8_t) { timer_.schedule(widen(when)); }

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

}  // namespace

void StepScheduler::on_step_timer() {
  HalStepPort port(timer_, pins_, timer_.now());
  run_step_interrupt(engine_, port);
}

}  // namespace hmc::fw
