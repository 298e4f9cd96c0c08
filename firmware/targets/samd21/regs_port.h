// SAMD21 PORT (GPIO and pin multiplexing) and EIC (external interrupts) registers. Bases:
// HARDWARE.md (PORT 0x41004400 with its single-cycle IOBUS alias 0x60000000, EIC 0x40001800);
// offsets and bits: SAMD21 datasheet, chapters "PORT" and "EIC".
#pragma once

#include <stdint.h>

namespace hmc::samd21 {

namespace port {
inline constexpr uint32_t kBase = 0x41004400;
inline constexpr uint32_t kIobusBase = 0x60000000;  // same registers, one-cycle access
inline constexpr uint32_t kGroupStride = 0x80;      // PA = group 0, PB = group 1
inline constexpr uint32_t kDirClr = 0x04;
inline constexpr uint32_t kDirSet = 0x08;
inline constexpr uint32_t kOutClr = 0x14;
inline constexpr uint32_t kOutSet = 0x18;
inline constexpr uint32_t kIn = 0x20;
inline constexpr uint32_t kCtrl = 0x24;    // SAMPLING: bit n = continuous sampling of pin n
inline constexpr uint32_t kPmux = 0x30;    // one byte per pin pair: even pin 3:0, odd pin 7:4
inline constexpr uint32_t kPinCfg = 0x40;  // one byte per pin
inline constexpr uint32_t kPinCfgPmuxEn = 1u << 0;
inline constexpr uint32_t kPinCfgInEn = 1u << 1;
inline constexpr uint32_t kPinCfgPullEn = 1u << 2;  // pull direction follows OUT (1 = up)

// Peripheral functions for PMUX (datasheet "I/O Multiplexing").
enum class Function : uint8_t {
  kA_Eic = 0,
  kB_Analog = 1,
  kC_Sercom = 2,
  kD_SercomAlt = 3,
  kE_TcTcc = 4,
  kF_Tcc = 5,
};
}  // namespace port

namespace eic {
inline constexpr uint32_t kBase = 0x40001800;
inline constexpr uint32_t kCtrl = kBase + 0x00;     // 8-bit: SWRST 0, ENABLE 1
inline constexpr uint32_t kStatus = kBase + 0x01;   // 8-bit: SYNCBUSY 7
inline constexpr uint32_t kIntEnClr = kBase + 0x08;
inline constexpr uint32_t kIntEnSet = kBase + 0x0C;
inline constexpr uint32_t kIntFlag = kBase + 0x10;
inline constexpr uint32_t kConfig0 = kBase + 0x18;  // EXTINT 0-7, 4 bits each; CONFIG1: 8-15
inline constexpr uint32_t kSwRst = 1u << 0;
inline constexpr uint32_t kEnable = 1u << 1;
inline constexpr uint32_t kSyncBusy = 1u << 7;
inline constexpr uint32_t kSenseBoth = 0x3;  // SENSE 2:0 = both edges
inline constexpr uint32_t kFilterEnable = 0x8;
}  // namespace eic

}  // namespace hmc::samd21
