// SAMD21 system registers this port uses: PM, SYSCTRL, GCLK, NVMCTRL, WDT, and the Cortex-M0+
// core's NVIC, SCB and SysTick. Bases and IRQ numbers: HARDWARE.md (SAMD21G18); offsets and
// bits: SAMD21 datasheet (DS40001882), chapters PM, SYSCTRL, GCLK, NVMCTRL, WDT, and the ARMv6-M
// Architecture Reference Manual (NVIC, SCB, SysTick). Only what the port touches is defined.
#pragma once

#include <stdint.h>

namespace hmc::samd21 {

// ---- PM: power manager, bus clock masks (datasheet "PM - Power Manager") ---------------
namespace pm {
inline constexpr uint32_t kBase = 0x40000400;
inline constexpr uint32_t kCpuSel = kBase + 0x08;   // 8-bit dividers, 0 = /1; APBASEL,
inline constexpr uint32_t kApbASel = kBase + 0x09;  // APBBSEL and APBCSEL follow
inline constexpr uint32_t kApbBSel = kBase + 0x0A;
inline constexpr uint32_t kApbCSel = kBase + 0x0B;
inline constexpr uint32_t kApbAMask = kBase + 0x18;
inline constexpr uint32_t kApbBMask = kBase + 0x1C;
inline constexpr uint32_t kApbCMask = kBase + 0x20;
inline constexpr uint32_t kApbAEic = 1u << 6;
inline constexpr uint32_t kApbAWdt = 1u << 4;
inline constexpr uint32_t kApbBPort = 1u << 3;
inline constexpr uint32_t kApbBDmac = 1u << 4;
inline constexpr uint32_t kApbCSercom0 = 1u << 2;  // SERCOMn: bit 2 + n (HARDWARE.md)
inline constexpr uint32_t kApbCTcc0 = 1u << 8;
inline constexpr uint32_t kApbCTcc1 = 1u << 9;
inline constexpr uint32_t kApbCTcc2 = 1u << 10;
inline constexpr uint32_t kApbCTc3 = 1u << 11;
inline constexpr uint32_t kApbCTc4 = 1u << 12;
inline constexpr uint32_t kApbCTc5 = 1u << 13;
inline constexpr uint32_t kAhbMask = kBase + 0x14;
inline constexpr uint32_t kAhbDmac = 1u << 5;
// RCAUSE (8-bit, read-only): the cause of the last reset, one bit (Microchip's register
// description, PM RCAUSE; reset value 0x01).
inline constexpr uint32_t kRcause = kBase + 0x38;
inline constexpr uint32_t kRcausePor = 1u << 0;
inline constexpr uint32_t kRcauseBod12 = 1u << 1;
inline constexpr uint32_t kRcauseBod33 = 1u << 2;
inline constexpr uint32_t kRcauseExt = 1u << 4;
inline constexpr uint32_t kRcauseWdt = 1u << 5;
inline constexpr uint32_t kRcauseSyst = 1u << 6;  // a system reset request (AIRCR.SYSRESETREQ)
}  // namespace pm

// ---- SYSCTRL: oscillators and the DFLL48M (datasheet "SYSCTRL") -------------------------
namespace sysctrl {
inline constexpr uint32_t kBase = 0x40000800;
inline constexpr uint32_t kPclkSr = kBase + 0x0C;      // status
inline constexpr uint32_t kXosc32k = kBase + 0x14;     // 16-bit
inline constexpr uint32_t kOsc8m = kBase + 0x20;       // 32-bit
inline constexpr uint32_t kDfllCtrl = kBase + 0x24;    // 16-bit
inline constexpr uint32_t kDfllVal = kBase + 0x28;
inline constexpr uint32_t kDfllMul = kBase + 0x2C;

// PCLKSR bits.
inline constexpr uint32_t kXosc32kRdy = 1u << 1;
inline constexpr uint32_t kOsc8mRdy = 1u << 3;
inline constexpr uint32_t kDfllRdy = 1u << 4;
inline constexpr uint32_t kDfllLckF = 1u << 6;
inline constexpr uint32_t kDfllLckC = 1u << 7;

// XOSC32K bits.
inline constexpr uint32_t kXosc32kEnable = 1u << 1;
inline constexpr uint32_t kXosc32kXtalEn = 1u << 2;
inline constexpr uint32_t kXosc32kEn32k = 1u << 3;
inline constexpr uint32_t kXosc32kAampEn = 1u << 5;
constexpr uint32_t xosc32k_startup(uint32_t code) { return (code & 0x7u) << 8; }  // 4: ~0.5 s

// OSC8M: PRESC bits 9:8 (0 = 8 MHz; reset value 3 = 1 MHz).
inline constexpr uint32_t kOsc8mPrescMask = 0x3u << 8;

// DFLLCTRL bits. Reset value has ONDEMAND set; it must be cleared before the DFLL is
// configured (datasheet errata, DFLL48M).
inline constexpr uint32_t kDfllEnable = 1u << 1;
inline constexpr uint32_t kDfllModeClosed = 1u << 2;
inline constexpr uint32_t kDfllWaitLock = 1u << 11;

// DFLLVAL: FINE 9:0, COARSE 15:10. DFLLMUL: MUL 15:0, FSTEP 25:16, CSTEP 31:26.
constexpr uint32_t dfll_val(uint32_t coarse, uint32_t fine) {
  return ((coarse & 0x3Fu) << 10) | (fine & 0x3FFu);
}
constexpr uint32_t dfll_mul(uint32_t mul, uint32_t fstep, uint32_t cstep) {
  return ((cstep & 0x3Fu) << 26) | ((fstep & 0x3FFu) << 16) | (mul & 0xFFFFu);
}
// Factory DFLL48M coarse calibration: NVM software calibration area, word 0x00806024 bits
// 31:26 (HARDWARE.md).
inline constexpr uint32_t kOtpDfllCoarseWord = 0x00806024;
inline constexpr uint32_t kOtpDfllCoarseShift = 26;
}  // namespace sysctrl

// ---- GCLK: generic clock generators and peripheral channels (datasheet "GCLK") ----------
namespace gclk {
inline constexpr uint32_t kBase = 0x40000C00;
inline constexpr uint32_t kStatus = kBase + 0x01;   // 8-bit, SYNCBUSY bit 7
inline constexpr uint32_t kClkCtrl = kBase + 0x02;  // 16-bit
inline constexpr uint32_t kGenCtrl = kBase + 0x04;  // 32-bit
inline constexpr uint32_t kGenDiv = kBase + 0x08;   // 32-bit
inline constexpr uint32_t kSyncBusy = 1u << 7;

// Sources for GENCTRL.SRC.
inline constexpr uint32_t kSrcOscUlp32k = 0x03;
inline constexpr uint32_t kSrcXosc32k = 0x05;
inline constexpr uint32_t kSrcOsc8m = 0x06;
inline constexpr uint32_t kSrcDfll48m = 0x07;

// Peripheral channel ids (CLKCTRL.ID), HARDWARE.md.
inline constexpr uint32_t kIdDfll48mRef = 0x00;
inline constexpr uint32_t kIdWdt = 0x03;
inline constexpr uint32_t kIdEic = 0x05;
inline constexpr uint32_t kIdSercom0 = 0x14;  // SERCOMn: 0x14 + n
inline constexpr uint32_t kIdTcc0Tcc1 = 0x1A;
inline constexpr uint32_t kIdTcc2Tc3 = 0x1B;
inline constexpr uint32_t kIdTc4Tc5 = 0x1C;

constexpr uint32_t genctrl(uint32_t generator, uint32_t source, bool divsel) {
  return (generator & 0xFu) | ((source & 0x1Fu) << 8) | (1u << 16) /* GENEN */ |
         (1u << 17) /* IDC: 50 % duty for odd dividers */ | (divsel ? (1u << 20) : 0u);
}
constexpr uint32_t gendiv(uint32_t generator, uint32_t div) {
  return (generator & 0xFu) | ((div & 0xFFFFu) << 8);
}
constexpr uint16_t clkctrl(uint32_t id, uint32_t generator) {
  return static_cast<uint16_t>((id & 0x3Fu) | ((generator & 0xFu) << 8) | (1u << 14) /* CLKEN */);
}
}  // namespace gclk

// ---- NVMCTRL (datasheet "NVMCTRL"): CTRLB.RWS, read wait states (1 at 48 MHz, 3.3 V) -----
namespace nvmctrl {
inline constexpr uint32_t kCtrlB = 0x41004000 + 0x04;
inline constexpr uint32_t kRwsMask = 0xFu << 1;
constexpr uint32_t rws(uint32_t states) { return (states & 0xFu) << 1; }
}  // namespace nvmctrl

// ---- WDT (datasheet "WDT") ---------------------------------------------------------------
namespace wdt {
inline constexpr uint32_t kBase = 0x40001000;
inline constexpr uint32_t kCtrl = kBase + 0x00;    // ENABLE bit 1
inline constexpr uint32_t kConfig = kBase + 0x01;  // PER 3:0
inline constexpr uint32_t kStatus = kBase + 0x07;  // SYNCBUSY bit 7
inline constexpr uint32_t kClear = kBase + 0x08;
inline constexpr uint32_t kEnable = 1u << 1;
inline constexpr uint32_t kSyncBusy = 1u << 7;
inline constexpr uint8_t kClearKey = 0xA5;
}  // namespace wdt

// ---- Cortex-M0+ core (ARMv6-M ARM: NVIC, SCB, SysTick) -----------------------------------
namespace nvic {
inline constexpr uint32_t kIser = 0xE000E100;
inline constexpr uint32_t kIcer = 0xE000E180;
inline constexpr uint32_t kIspr = 0xE000E200;
inline constexpr uint32_t kIcpr = 0xE000E280;
inline constexpr uint32_t kIpr0 = 0xE000E400;  // word access only on ARMv6-M
}  // namespace nvic
namespace scb {
inline constexpr uint32_t kIcsr = 0xE000ED04;
inline constexpr uint32_t kIcsrPendStClr = 1u << 25;  // clears a pending SysTick exception
inline constexpr uint32_t kVtor = 0xE000ED08;
inline constexpr uint32_t kAircr = 0xE000ED0C;
inline constexpr uint32_t kAircrSysReset = (0x05FAu << 16) | (1u << 2);  // VECTKEY | SYSRESETREQ
}  // namespace scb
namespace systick {
inline constexpr uint32_t kCsr = 0xE000E010;  // ENABLE 0, CLKSOURCE 2, COUNTFLAG 16
inline constexpr uint32_t kRvr = 0xE000E014;
inline constexpr uint32_t kCvr = 0xE000E018;
inline constexpr uint32_t kEnableCpuClock = (1u << 0) | (1u << 2);
inline constexpr uint32_t kCountFlag = 1u << 16;
}  // namespace systick

// SAMD21 interrupt numbers (HARDWARE.md: EIC 4, DMAC 6, SERCOMn 9+n, TCCn 15+n, TC3-5 18-20).
namespace irqn {
inline constexpr uint32_t kEic = 4;
inline constexpr uint32_t kDmac = 6;
inline constexpr uint32_t kSercom0 = 9;
inline constexpr uint32_t kTcc0 = 15;
inline constexpr uint32_t kTcc1 = 16;
inline constexpr uint32_t kTcc2 = 17;
inline constexpr uint32_t kTc3 = 18;
inline constexpr uint32_t kTc4 = 19;
}  // namespace irqn

}  // namespace hmc::samd21
