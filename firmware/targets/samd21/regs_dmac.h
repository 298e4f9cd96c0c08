// SAMD21 DMAC registers and the transfer descriptor layout. Base: HARDWARE.md (DMAC 0x41004800,
// SERCOMn TX trigger 2n+2); offsets, bits and the 16-byte descriptor: SAMD21 datasheet, "DMAC".
#pragma once

#include <stdint.h>

namespace hmc::samd21::dmac {

inline constexpr uint32_t kBase = 0x41004800;
inline constexpr uint32_t kCtrl = kBase + 0x00;      // 16-bit: SWRST 0, DMAENABLE 1, LVLENx 8+x
inline constexpr uint32_t kBaseAddr = kBase + 0x34;  // descriptor section (16 bytes per channel)
inline constexpr uint32_t kWrbAddr = kBase + 0x38;   // write-back section
inline constexpr uint32_t kChId = kBase + 0x3F;      // selects the channel for CH* registers
inline constexpr uint32_t kChCtrlA = kBase + 0x40;   // 8-bit: SWRST 0, ENABLE 1
inline constexpr uint32_t kChCtrlB = kBase + 0x44;
inline constexpr uint32_t kChIntFlag = kBase + 0x4E;  // TERR 0, TCMPL 1, SUSP 2

inline constexpr uint32_t kCtrlSwRst = 1u << 0;
inline constexpr uint32_t kCtrlEnableAllLevels = (1u << 1) | (0xFu << 8);
inline constexpr uint32_t kChEnable = 1u << 1;
inline constexpr uint32_t kChSwRst = 1u << 0;

// CHCTRLB: LVL 6:5 (arbitration level: a higher level is served first), TRIGSRC 13:8, TRIGACT
// 23:22 (2 = one beat per trigger).
constexpr uint32_t chctrlb_beat_trigger(uint32_t trigger, uint32_t level = 0) {
  return ((level & 3u) << 5) | ((trigger & 0x3Fu) << 8) | (2u << 22);
}
constexpr uint32_t sercom_tx_trigger(uint32_t sercom) { return 2u * sercom + 2u; }
// TRIGSRC of the step compares' matches (datasheet "DMAC", CHCTRLB.TRIGSRC table: TCC1 OVF 0x12,
// MC0 0x13, MC1 0x14; TCC2 OVF 0x15, MC0 0x16, MC1 0x17; TC4 OVF 0x1B, MC0 0x1C, MC1 0x1D).
inline constexpr uint32_t kTriggerTcc1Mc0 = 0x13;
inline constexpr uint32_t kTriggerTcc1Mc1 = 0x14;
inline constexpr uint32_t kTriggerTcc2Mc0 = 0x16;
inline constexpr uint32_t kTriggerTcc2Mc1 = 0x17;
inline constexpr uint32_t kTriggerTc4Mc0 = 0x1C;
inline constexpr uint32_t kTriggerTc4Mc1 = 0x1D;

// Transfer descriptor (BTCTRL, BTCNT, SRCADDR, DSTADDR, DESCADDR). SRCADDR of an incrementing
// source is the address just past the block's last beat.
struct alignas(16) Descriptor {
  uint16_t btctrl;
  uint16_t btcnt;
  uint32_t srcaddr;
  uint32_t dstaddr;
  uint32_t descaddr;
};
static_assert(sizeof(Descriptor) == 16, "the DMAC reads 16-byte descriptors");

// BTCTRL: VALID 0, BLOCKACT 4:3 (0: disable the channel after the last block), BEATSIZE 9:8
// (0 = byte), SRCINC 10.
inline constexpr uint16_t kBtValidByteSrcInc = static_cast<uint16_t>((1u << 0) | (1u << 10));
// One word from a fixed source (BEATSIZE 2 = word, no increment).
inline constexpr uint16_t kBtValidWord = static_cast<uint16_t>((1u << 0) | (2u << 8));

}  // namespace hmc::samd21::dmac
