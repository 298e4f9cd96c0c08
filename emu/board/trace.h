// The emulated board's trace: one JSON object per line, in hmc-sim's format (docs/sim.md,
// "Trace"; the event kinds at the top of firmware/targets/sim/sim_board.h), so the same tooling
// reads both. The devices (board.h) write what they decode from the pins; the time `t` is in
// 48 MHz ticks since the first power-on, as hmc-sim's.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>

namespace hmc::emu {

class Trace {
 public:
  explicit Trace(std::ostream& out) : out_(out) {}
  // The virtual time at which the current power cycle's chip time 0 falls (a reset restarts the
  // chip's clock; the trace's clock runs on).
  void set_offset_ps(uint64_t offset_ps) { offset_ps_ = offset_ps; }
  // One event at chip time `ps`; `fields` is the object's body after "t" (no braces).
  void event(uint64_t ps, const std::string& fields);
  void flush() { out_.flush(); }

 private:
  std::ostream& out_;
  uint64_t offset_ps_ = 0;
};

// "true"/"false" for a field.
inline const char* json_flag(bool value) { return value ? "true" : "false"; }

}  // namespace hmc::emu
