// Why the chip last reset, and where a fault happened. The fault handler (every exception or
// interrupt without a handler of its own, startup.cpp) stores the stacked PC, LR and xPSR and
// the exception that caught it in a RAM record that start-up does not clear (.noinit), then
// requests a system reset. At boot, reset_report_take() reads PM RCAUSE and the record (and
// clears it) for the boot event.
//
// The record survives a system reset because RAM keeps its contents through one (only a
// power-on loses them); a check word over its fields rejects the random contents of RAM after
// power-on, or a record a bootloader overwrote on its way back to the application (then the
// reset reads as "software", the cause RCAUSE gives).
#pragma once

#include <stdint.h>

#include "core/controller.h"

namespace hmc::samd21 {

fw::ResetReport reset_report_take();

}  // namespace hmc::samd21

// The fault handlers' second half: records `frame` (the 8 words the exception entry stacked)
// and resets. Called from the naked entry in startup.cpp with the stack it used.
extern "C" [[noreturn]] void record_fault_and_reset(const uint32_t* frame);
