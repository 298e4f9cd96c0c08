// The board's trace (trace.h).
#include "trace.h"

namespace hmc::emu {

void Trace::event(uint64_t ps, const std::string& fields) {
  // 48 ticks per µs (hmc-sim's timer clock): ps · 48 / 10^6.
  const uint64_t ticks = (offset_ps_ + ps) / 1000000u * 48u + (offset_ps_ + ps) % 1000000u * 48u / 1000000u;
  out_ << "{\"t\":" << ticks << ',' << fields << "}\n";
}

}  // namespace hmc::emu
