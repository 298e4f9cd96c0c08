// SAMD21 TC (16/32-bit timer/counter) and TCC (timer/counter for control) registers. Bases,
// IRQs and clock ids: HARDWARE.md (TCC0 0x42002000, TC3/4/5 0x42002C00/0x42003000/0x42003400);
// offsets and bits: SAMD21 datasheet, "TC" and "TCC" register summaries.
#pragma once

#include <stdint.h>

namespace hmc::samd21 {

namespace tc {
inline constexpr uint32_t kTc3 = 0x42002C00;
inline constexpr uint32_t kTc4 = 0x42003000;
inline constexpr uint32_t kTc5 = 0x42003400;
// Offsets.
inline constexpr uint32_t kCtrlA = 0x00;    // 16-bit
inline constexpr uint32_t kReadReq = 0x02;  // 16-bit: ADDR 4:0, RCONT 14, RREQ 15
inline constexpr uint32_t kIntEnClr = 0x0C;
inline constexpr uint32_t kIntEnSet = 0x0D;
inline constexpr uint32_t kIntFlag = 0x0E;
inline constexpr uint32_t kStatus = 0x0F;   // SYNCBUSY bit 7
inline constexpr uint32_t kCount = 0x10;    // 16 or 32 bits by mode
inline constexpr uint32_t kCc0 = 0x18;      // 16 or 32 bits by mode
inline constexpr uint32_t kCc1 = 0x1C;      // 32-bit mode (0x1A in 16-bit mode)
// CTRLA fields.
inline constexpr uint32_t kSwRst = 1u << 0;
inline constexpr uint32_t kEnable = 1u << 1;
inline constexpr uint32_t kMode16 = 0u << 2;
inline constexpr uint32_t kMode32 = 2u << 2;   // TC4 + TC5 as one 32-bit counter
inline constexpr uint32_t kWaveMfrq = 1u << 5;  // match frequency: WO[0] toggles on CC0
constexpr uint32_t prescaler(uint32_t code) { return (code & 7u) << 8; }  // 0 /1, 3 /8, 5 /64
// READREQ: request a synchronised read of COUNT.
inline constexpr uint16_t kReadCount = static_cast<uint16_t>((1u << 15) | kCount);
// INTFLAG bits.
inline constexpr uint32_t kIntOvf = 1u << 0;
inline constexpr uint32_t kIntMc0 = 1u << 4;
inline constexpr uint32_t kIntMc1 = 1u << 5;
inline constexpr uint32_t kSyncBusy = 1u << 7;
}  // namespace tc

namespace tcc {
inline constexpr uint32_t kTcc0 = 0x42002000;
inline constexpr uint32_t kTcc1 = 0x42002400;  // 24-bit counter, CC0 and CC1
inline constexpr uint32_t kTcc2 = 0x42002800;  // 16-bit counter, CC0 and CC1
// Offsets.
inline constexpr uint32_t kCtrlA = 0x00;
inline constexpr uint32_t kCtrlBSet = 0x05;  // 8-bit: CMD 7:5
inline constexpr uint32_t kSyncBusy = 0x08;
inline constexpr uint32_t kIntEnClr = 0x24;
inline constexpr uint32_t kIntEnSet = 0x28;
inline constexpr uint32_t kIntFlag = 0x2C;   // OVF 0, MC0 16, MC1 17 (write 1 to clear)
inline constexpr uint32_t kCount = 0x34;     // 24 bits
inline constexpr uint32_t kWave = 0x3C;
inline constexpr uint32_t kPer = 0x40;
constexpr uint32_t cc(uint32_t n) { return 0x44u + 4u * n; }
constexpr uint32_t ccb(uint32_t n) { return 0x70u + 4u * n; }  // buffered: applied at period end
// CTRLA fields.
inline constexpr uint32_t kSwRst = 1u << 0;
inline constexpr uint32_t kEnable = 1u << 1;
constexpr uint32_t prescaler(uint32_t code) { return (code & 7u) << 8; }  // 4 = /16
// CTRLBSET.CMD = READSYNC: copy the counter into COUNT for reading (done when SYNCBUSY.CTRLB
// and SYNCBUSY.COUNT clear).
inline constexpr uint8_t kCmdReadSync = 4u << 5;
inline constexpr uint32_t kIntOvf = 1u << 0;  // a period ended (the counter wrapped to zero)
inline constexpr uint32_t kIntMc0 = 1u << 16;  // the counter reached CC0
inline constexpr uint32_t kIntMc1 = 1u << 17;
// WAVE: WAVEGEN 2:0, 2 = normal (single-slope) PWM.
inline constexpr uint32_t kWaveNpwm = 2u;
// SYNCBUSY bits.
inline constexpr uint32_t kSyncSwRst = 1u << 0;
inline constexpr uint32_t kSyncEnable = 1u << 1;
inline constexpr uint32_t kSyncCtrlB = 1u << 2;
inline constexpr uint32_t kSyncCount = 1u << 4;
inline constexpr uint32_t kSyncWave = 1u << 6;
inline constexpr uint32_t kSyncPer = 1u << 7;
constexpr uint32_t sync_cc(uint32_t n) { return 1u << (8u + n); }
}  // namespace tcc

}  // namespace hmc::samd21
