// The reset cause and the fault record (reset_cause.h). RCAUSE: Microchip's register
// description (PM, RCAUSE); the exception frame: ARMv6-M Architecture Reference Manual,
// "Exception entry behavior" (R0-R3, R12, LR, the return address, xPSR, 8-byte aligned) and
// IPSR (the exception number being handled, bits 5:0 of xPSR).
#include "reset_cause.h"

#include "reg_access.h"
#include "regs_system.h"

namespace hmc::samd21 {
namespace {

constexpr uint32_t kMagic = 0x46A17C0Du;
constexpr uint32_t kRamStart = 0x20000000u;
constexpr uint32_t kRamEnd = 0x20008000u;  // SAMD21G18: 32 KB

struct FaultRecord {
  uint32_t magic;
  uint32_t pc;
  uint32_t lr;
  uint32_t xpsr;
  uint32_t exception;
  uint32_t check;
};

__attribute__((section(".noinit"))) FaultRecord fault_record;

uint32_t check_of(const FaultRecord& r) { return ~(r.magic ^ r.pc ^ r.lr ^ r.xpsr ^ r.exception); }

}  // namespace

fw::ResetReport reset_report_take() {
  fw::ResetReport report;
  const uint32_t rcause = r8(pm::kRcause);
  if ((rcause & pm::kRcausePor) != 0) {
    report.cause = proto::ResetCause::kPowerOn;
  } else if ((rcause & (pm::kRcauseBod12 | pm::kRcauseBod33)) != 0) {
    report.cause = proto::ResetCause::kBrownOut;
  } else if ((rcause & pm::kRcauseExt) != 0) {
    report.cause = proto::ResetCause::kExternal;
  } else if ((rcause & pm::kRcauseWdt) != 0) {
    report.cause = proto::ResetCause::kWatchdog;
  } else if ((rcause & pm::kRcauseSyst) != 0) {
    report.cause = proto::ResetCause::kSoftware;
  }
  const FaultRecord r = fault_record;
  fault_record.magic = 0;  // reported once
  if (report.cause == proto::ResetCause::kSoftware && r.magic == kMagic && r.check == check_of(r)) {
    report.cause = proto::ResetCause::kFault;
    report.exception = r.exception;
    report.pc = r.pc;
    report.lr = r.lr;
    report.context = r.xpsr & 0x3Fu;
  }
  return report;
}

}  // namespace hmc::samd21

extern "C" void record_fault_and_reset(const uint32_t* frame) {
  using namespace hmc::samd21;
  uint32_t ipsr;
  __asm__ volatile("mrs %0, ipsr" : "=r"(ipsr));
  FaultRecord r{kMagic, 0, 0, 0, ipsr & 0x3Fu, 0};
  // A stack pointer outside RAM (a stack overflow past the bottom of RAM) cannot be read: a
  // fault in here would lock the core up until the watchdog resets it, with no record.
  const auto at = reinterpret_cast<uint32_t>(frame);
  if (at >= kRamStart && at <= kRamEnd - 8u * sizeof(uint32_t) && (at & 3u) == 0) {
    r.lr = frame[5];
    r.pc = frame[6];
    r.xpsr = frame[7];
  }
  r.check = check_of(r);
  fault_record = r;
  __asm__ volatile("dsb" ::: "memory");  // the record is in RAM before the reset
  r32(scb::kAircr) = scb::kAircrSysReset;
  for (;;) {
  }
}
