// DMA channels (dma.h). Register and descriptor layout: regs_dmac.h (SAMD21 datasheet "DMAC").
// A single-block transfer whose descriptor has no successor disables its channel when done, so
// CHCTRLA.ENABLE reading 0 means finished.
#include "dma.h"

#include "reg_access.h"
#include "regs_dmac.h"
#include "regs_system.h"

namespace hmc::samd21 {
namespace {

// The DMAC fetches channel n's descriptor from base + 16n and writes its state back to
// write-back + 16n: both sections in RAM, 16-byte aligned, one entry per channel used (the
// highest channel used + 1: kDmaChannels).
dmac::Descriptor descriptors[kDmaChannels];
dmac::Descriptor writeback[kDmaChannels];

// Enables `channel` with CHCTRLB `chctrlb`, its descriptor already written.
void enable_channel(uint32_t channel, uint32_t chctrlb) {
  r8(dmac::kChId) = static_cast<uint8_t>(channel);
  r8(dmac::kChCtrlA) = 0;
  r32(dmac::kChCtrlB) = chctrlb;
  r8(dmac::kChIntFlag) = 0x7;  // clear TERR, TCMPL, SUSP
  // The descriptor and the buffer are plain RAM: they must be written before the channel runs.
  __asm__ volatile("dmb" ::: "memory");
  r8(dmac::kChCtrlA) = static_cast<uint8_t>(dmac::kChEnable);
}

}  // namespace

void dma_init() {
  set32(pm::kAhbMask, pm::kAhbDmac);
  set32(pm::kApbBMask, pm::kApbBDmac);
  r16(dmac::kCtrl) = 0;
  r16(dmac::kCtrl) = static_cast<uint16_t>(dmac::kCtrlSwRst);
  while ((r16(dmac::kCtrl) & dmac::kCtrlSwRst) != 0) {
  }
  r32(dmac::kBaseAddr) = reinterpret_cast<uint32_t>(&descriptors[0]);
  r32(dmac::kWrbAddr) = reinterpret_cast<uint32_t>(&writeback[0]);
  r16(dmac::kCtrl) = static_cast<uint16_t>(dmac::kCtrlEnableAllLevels);
}

void dma_start(uint32_t channel, const uint8_t* source, uint16_t count, uint32_t destination,
               uint32_t trigger) {
  dmac::Descriptor& d = descriptors[channel];
  d.btctrl = dmac::kBtValidByteSrcInc;
  d.btcnt = count;
  d.srcaddr = reinterpret_cast<uint32_t>(source) + count;
  d.dstaddr = destination;
  d.descaddr = 0;
  enable_channel(channel, dmac::chctrlb_beat_trigger(trigger));
}

void dma_start_endless_word(uint32_t channel, const volatile uint32_t* source, uint32_t destination,
                            uint32_t trigger, uint32_t level) {
  dmac::Descriptor& d = descriptors[channel];
  d.btctrl = dmac::kBtValidWord;
  d.btcnt = 1;
  d.srcaddr = reinterpret_cast<uint32_t>(source);  // no increment: the address itself
  d.dstaddr = destination;
  d.descaddr = reinterpret_cast<uint32_t>(&d);  // the next block is this one again
  enable_channel(channel, dmac::chctrlb_beat_trigger(trigger, level));
}

bool dma_busy(uint32_t channel) {
  r8(dmac::kChId) = static_cast<uint8_t>(channel);
  return (r8(dmac::kChCtrlA) & dmac::kChEnable) != 0;
}

}  // namespace hmc::samd21
