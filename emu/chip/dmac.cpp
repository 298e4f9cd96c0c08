// DMAC (dmac.h). Registers (20.8): CTRL 0x00, BASEADDR 0x34, WRBADDR 0x38, CHID 0x3F,
// CHCTRLA 0x40, CHCTRLB 0x44, CHINTENCLR 0x4C, CHINTENSET 0x4D, CHINTFLAG 0x4E. Descriptor
// (20.10): BTCTRL 0x00 (VALID 0, EVOSEL 2:1, BLOCKACT 4:3, BEATSIZE 9:8, SRCINC 10, DSTINC 11,
// STEPSEL 12, STEPSIZE 15:13), BTCNT 0x02, SRCADDR 0x04, DSTADDR 0x08, DESCADDR 0x0C.
#include "dmac.h"

#include <algorithm>

#include "sercom.h"
#include "timers.h"

namespace hmc::emu {
namespace {

// From a timer's compare match to the beat's write landing in its register, in CPU cycles: the
// datasheet gives no figure (arbitration, the source read from SRAM, the write through the
// AHB-APB bridge). A GUESS, listed with the emulator's other guesses (docs/emu.md, "Assumptions
// and the error they imply"). Both edges of a STEP pulse go through it, so the pulse's width
// does not depend on it; the step's time is this much after the compare.
constexpr uint64_t kTriggerToWriteCycles = 5;

constexpr unsigned kTriggerOf(uint32_t ctrlb) { return (ctrlb >> 8) & 0x3F; }
// CHCTRLB.LVL (bits 6:5): "the arbitration level used for the DMA channel, where a high level has
// priority over a low level" (20.8.17).
constexpr unsigned kLevelOf(uint32_t ctrlb) { return (ctrlb >> 5) & 3; }
// SERCOMn TX trigger 2n+2 (20.8.17, TRIGSRC).
constexpr bool is_sercom_tx(unsigned trigger) {
  return trigger >= 2 && trigger <= 12 && trigger % 2 == 0;
}
// The compare channel of `timer` whose match is DMAC trigger `trigger`, or -1: MC0, MC1, ... follow
// the timer's OVF trigger (20.8.17, TRIGSRC; chip.cpp gives each timer its base).
int match_channel(const DmaTimer& timer, unsigned trigger) {
  const unsigned mc0 = timer.dma_trigger_base() + 1;
  return trigger >= mc0 && trigger < mc0 + timer.compare_channels() ? static_cast<int>(trigger - mc0)
                                                                     : -1;
}

uint32_t word_at(const uint8_t* d) {
  return uint32_t{d[0]} | uint32_t{d[1]} << 8 | uint32_t{d[2]} << 16 | uint32_t{d[3]} << 24;
}

}  // namespace

bool Dmac::irq() const {
  for (const Channel& c : channels_) {
    if ((c.intflag & c.inten) != 0) return true;
  }
  return false;
}

uint32_t Dmac::read(uint32_t offset, unsigned size) {
  const Channel& c = channels_[chid_ % kChannels];
  RegisterBytes view(0x50);
  view.set(0x00, ctrl_, 2);
  view.set(0x34, base_, 4);
  view.set(0x38, writeback_, 4);
  view.set(0x3F, chid_, 1);
  view.set(0x40, c.ctrla, 1);
  view.set(0x44, c.ctrlb, 4);
  view.set(0x4C, c.inten, 1);
  view.set(0x4D, c.inten, 1);
  view.set(0x4E, c.intflag, 1);
  view.set(0x4F, c.active ? 3 : 0, 1);  // CHSTATUS: PEND, BUSY
  return view.get(offset, size);
}

void Dmac::write(uint32_t offset, uint32_t value, unsigned size) {
  RegisterBytes view(0x50);
  view.set(offset, value, size);
  if (touches(offset, size, 0x00, 2)) {
    const uint16_t v = static_cast<uint16_t>(view.get(0, 2));
    if ((v & 1) != 0) {  // SWRST (20.8.1)
      ctrl_ = 0;
      base_ = writeback_ = 0;
      channels_ = {};
      watch_timers();
    } else {
      ctrl_ = v;
    }
  }
  if (touches(offset, size, 0x34, 4)) {
    if ((ctrl_ & 2) != 0) {
      chip_.violation("write to DMAC BASEADDR while DMAENABLE is set (20.8.13: enable-protected)");
      return;
    }
    base_ = view.get(0x34, 4);
  }
  if (touches(offset, size, 0x38, 4)) writeback_ = view.get(0x38, 4);
  if (touches(offset, size, 0x3F, 1)) chid_ = static_cast<uint8_t>(view.get(0x3F, 1));
  Channel& c = channels_[chid_ % kChannels];
  if (touches(offset, size, 0x44, 4)) c.ctrlb = view.get(0x44, 4);
  if (touches(offset, size, 0x4C, 1)) c.inten &= static_cast<uint8_t>(~view.get(0x4C, 1));
  if (touches(offset, size, 0x4D, 1)) c.inten |= static_cast<uint8_t>(view.get(0x4D, 1));
  if (touches(offset, size, 0x4E, 1)) c.intflag &= static_cast<uint8_t>(~view.get(0x4E, 1));
  if (touches(offset, size, 0x40, 1)) {
    const uint8_t v = static_cast<uint8_t>(view.get(0x40, 1));
    c.ctrla = v & 2;
    if ((v & 2) == 0) c.active = false;
    else if (!c.active) start(chid_ % kChannels);
    watch_timers();
  }
  chip_.irq_changed();
  chip_.reschedule();
}

void Dmac::start(unsigned channel) {
  Channel& c = channels_[channel];
  if ((ctrl_ & 2) == 0) {
    chip_.violation("DMAC channel enabled while the DMAC is off (CTRL.DMAENABLE clear)");
    return;
  }
  const unsigned trigger = kTriggerOf(c.ctrlb);
  const auto& timers = chip_.dma_timers();
  const bool timer_match = std::any_of(timers.begin(), timers.end(), [trigger](const DmaTimer* t) {
    return match_channel(*t, trigger) >= 0;
  });
  if (!is_sercom_tx(trigger) && !timer_match) {
    chip_.violation("DMAC trigger " + std::to_string(trigger) + " is not modelled");
    return;
  }
  // CHCTRLB.TRIGACT (bits 23:22): 2, one beat per trigger, is the only action modelled.
  if (((c.ctrlb >> 22) & 3) != 2) {
    chip_.violation("DMAC trigger actions other than BEAT (CHCTRLB.TRIGACT 2) are not modelled");
    return;
  }
  // "Each priority level x is enabled by setting the corresponding Priority Level x Enable bit in
  // the Control register (CTRL.LVLENx=1)" (20.6.2.4).
  if ((ctrl_ & (1u << (8 + kLevelOf(c.ctrlb)))) == 0) {
    chip_.violation("DMAC channel " + std::to_string(channel) + " enabled on a priority level "
                    "that CTRL.LVLENx leaves off (20.6.2.4)");
    return;
  }
  if (load(channel, base_ + 16 * channel)) c.active = true;
}

// 20.6.2.2 "Transfer Descriptors": the first descriptor is read from BASEADDR + 16·channel, the
// next from the DESCADDR of the one before, and the channel's descriptor in progress is written
// back to WRBADDR + 16·channel. SRCADDR of an incrementing source is the end of the block.
bool Dmac::load(unsigned channel, uint32_t address) {
  Channel& c = channels_[channel];
  uint8_t d[16];
  if (!chip_.memory().read(address, d, 16)) {
    chip_.violation("DMAC descriptor outside RAM");
    return false;
  }
  if (!chip_.memory().write(writeback_ + 16 * channel, d, 16)) {
    chip_.violation("DMAC write-back section outside RAM (WRBADDR + 16 x channel)");
    return false;
  }
  const uint16_t btctrl = static_cast<uint16_t>(d[0] | d[1] << 8);
  const uint16_t btcnt = static_cast<uint16_t>(d[2] | d[3] << 8);
  if ((btctrl & 1) == 0) {
    chip_.violation("DMAC channel " + std::to_string(channel) + " fetched an invalid "
                    "descriptor (BTCTRL.VALID clear)");
    return false;
  }
  const unsigned beatsize = (btctrl >> 8) & 3;  // 0 byte, 1 half-word, 2 word, 3 reserved
  if (beatsize == 3) {
    chip_.violation("DMAC descriptor with the reserved BEATSIZE 3");
    return false;
  }
  if ((btctrl & (1u << 11)) != 0 || (btctrl >> 13) != 0 || ((btctrl >> 1) & 3) != 0) {
    chip_.violation("DMAC destination increment, address steps and event output (BTCTRL "
                    "DSTINC, STEPSIZE, EVOSEL) are not modelled");
    return false;
  }
  if (btcnt == 0) {
    chip_.violation("DMAC descriptor with BTCNT 0 (not modelled)");
    return false;
  }
  if (is_sercom_tx(kTriggerOf(c.ctrlb)) && beatsize != 0) {
    chip_.violation("DMAC beats other than bytes into a SERCOM are not modelled");
    return false;
  }
  c.beat = 1u << beatsize;
  c.source_increments = (btctrl & (1u << 10)) != 0;
  c.block_interrupt = ((btctrl >> 3) & 1) != 0;  // BLOCKACT INT (1) or BOTH (3)
  c.remaining = btcnt;
  const uint32_t src = word_at(d + 4);
  c.source = c.source_increments ? src - btcnt * c.beat : src;
  c.destination = word_at(d + 8);
  c.next_descriptor = word_at(d + 12);
  return true;
}

// A block's last beat moved. "Transfer Complete (TCMPL)": set when a block with BLOCKACT INT or
// BOTH ends, and at the transfer's end; a DESCADDR of 0 marks the last block, after which the
// channel is disabled (BTCTRL.BLOCKACT NOACT: "Channel will be disabled if it is the last
// block transfer in the transaction"); otherwise the next descriptor is fetched (20.6.2.2).
void Dmac::block_done(unsigned i) {
  Channel& c = channels_[i];
  if (c.next_descriptor != 0) {
    if (c.block_interrupt) {
      c.intflag |= 2;
      chip_.irq_changed();
    }
    if (!load(i, c.next_descriptor)) c.active = false;
    return;
  }
  c.active = false;
  c.ctrla = 0;
  c.intflag |= 2;  // TCMPL
  chip_.irq_changed();
  watch_timers();
}

void Dmac::watch_timers() {
  for (DmaTimer* timer : chip_.dma_timers()) {
    unsigned watched = 0;  // bit x: MCx
    for (const Channel& c : channels_) {
      const int channel = c.active ? match_channel(*timer, kTriggerOf(c.ctrlb)) : -1;
      if (channel >= 0) watched |= 1u << channel;
    }
    timer->set_dma_watch(watched);
  }
}

void Dmac::advance(uint64_t) {
  for (unsigned i = 0; i < kChannels; ++i) {
    if (channels_[i].active && is_sercom_tx(kTriggerOf(channels_[i].ctrlb))) serve(i);
  }
}

void Dmac::sercom_ready(unsigned sercom) {
  for (unsigned i = 0; i < kChannels; ++i) {
    if (channels_[i].active && kTriggerOf(channels_[i].ctrlb) == 2 * sercom + 2) serve(i);
  }
}

// A SERCOM channel: one byte whenever DATA is empty (the DRE trigger).
void Dmac::serve(unsigned i) {
  Channel& c = channels_[i];
  Sercom& sercom = chip_.sercom((kTriggerOf(c.ctrlb) - 2) / 2);
  while (c.active && sercom.data_empty()) {
    uint8_t byte = 0;
    if (!chip_.memory().read(c.source, &byte, 1)) {
      chip_.violation("DMAC read outside memory");
      return;
    }
    sercom.dma_write(byte);
    if (c.source_increments) ++c.source;
    if (--c.remaining == 0) block_done(i);
  }
}

// 20.6.2.4 "Arbitration": channels with a pending trigger are granted by priority level, "a high
// level has priority over a low level" (20.8.17, CHCTRLB.LVL), and within a level, with static
// arbitration (PRICTRL0.RRLVLENx = 0, its reset value, which the image keeps), "the arbiter will
// prioritize a low channel number over a high channel number".
void Dmac::timer_trigger(const unsigned* triggers, unsigned trigger_count, uint64_t ps) {
  unsigned order[kChannels];
  unsigned count = 0;
  for (unsigned i = 0; i < kChannels; ++i) {
    if (!channels_[i].active) continue;
    const unsigned t = kTriggerOf(channels_[i].ctrlb);
    const unsigned* end = triggers + trigger_count;
    if (std::find(triggers, end, t) != end) order[count++] = i;
  }
  std::stable_sort(order, order + count, [this](unsigned a, unsigned b) {
    return kLevelOf(channels_[a].ctrlb) > kLevelOf(channels_[b].ctrlb);
  });
  const uint64_t hz = chip_.cpu_hz();
  const uint64_t latency = hz == 0 ? 0 : mul_div(kTriggerToWriteCycles, Chip::kPsPerSecond, hz);
  for (unsigned k = 0; k < count; ++k) beat(order[k], ps + latency);
}

// One beat: the source read from RAM, the destination written — a peripheral register through
// the bus like any other write (the PORT through the APB bridge: the IOBUS is the CPU's alone,
// datasheet 23.5.9), with the beat's own time as the access's time.
void Dmac::beat(unsigned i, uint64_t ps) {
  Channel& c = channels_[i];
  uint8_t bytes[4] = {};
  if (!chip_.memory().read(c.source, bytes, c.beat)) {
    chip_.violation("DMAC read outside memory");
    return;
  }
  const uint32_t value = word_at(bytes) & (c.beat == 4 ? 0xFFFFFFFFu : (1u << (8 * c.beat)) - 1u);
  // The access keeps the beat's time until its block's end is handled too (a TCC's
  // set_dma_watch advances it to that time). A beat may run inside another's write (a PORT write first lands
  // the beats triggered before it): the outer one's time is put back after.
  const uint64_t outer_ps = chip_.master_ps();
  chip_.set_master_ps(ps);
  if (c.destination >= 0x40000000u) {
    chip_.bus_write(c.destination, value, c.beat);
  } else if (!chip_.memory().write(c.destination, bytes, c.beat)) {
    chip_.violation("DMAC write outside memory");
    chip_.set_master_ps(outer_ps);
    return;
  }
  if (c.source_increments) c.source += c.beat;
  if (--c.remaining == 0) block_done(i);
  chip_.set_master_ps(outer_ps);
}

}  // namespace hmc::emu
