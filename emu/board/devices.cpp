// The pin devices (devices.h).
#include "devices.h"

#include <cstddef>

namespace hmc::emu {
namespace {

bool within(uint64_t value, uint64_t centre, uint64_t tolerance) {
  return value + tolerance >= centre && value <= centre + tolerance;
}

constexpr uint64_t kT0HPs = 300000, kT1HPs = 600000, kT0LPs = 900000, kT1LPs = 600000;

}  // namespace

void Sk6812Strip::level(bool high, uint64_t ps) {
  if (high == high_) return;
  if (ps < rise_ps_ || ps < fall_ps_) ps = rise_ps_ > fall_ps_ ? rise_ps_ : fall_ps_;  // never back in time
  high_ = high;
  if (high) {
    poll(ps);  // a reset gap before this edge latched what came before it
    if (!received_.empty()) {
      // The low that ended the previous bit (T0L or T1L).
      if (!within(ps - fall_ps_, last_bit_ ? kT1LPs : kT0LPs, kTolerancePs)) ++lows_off_;
    }
    rise_ps_ = ps;
    return;
  }
  fall_ps_ = ps;
  const uint64_t width = ps - rise_ps_;
  last_bit_ = width > kOneHighPs;
  if (!within(width, last_bit_ ? kT1HPs : kT0HPs, kTolerancePs)) ++highs_off_;
  received_.push_back(last_bit_);
  ++bits_total_;
}

uint64_t Sk6812Strip::latch_due_ps() const {
  return high_ || received_.empty() ? UINT64_MAX : fall_ps_ + kResetPs;
}

void Sk6812Strip::poll(uint64_t now_ps) {
  if (latch_due_ps() <= now_ps) latch(fall_ps_ + kResetPs);
}

void Sk6812Strip::latch(uint64_t at_ps) {
  Frame frame;
  frame.latched_ps = at_ps;
  const std::size_t complete = received_.size() / 32;
  for (std::size_t led = 0; led < complete && led < grbw_.size(); ++led) {
    for (std::size_t byte = 0; byte < 4; ++byte) {
      uint8_t value = 0;
      for (std::size_t bit = 0; bit < 8; ++bit) value = static_cast<uint8_t>(value << 1 | received_[32 * led + 8 * byte + bit]);
      grbw_[led][byte] = value;
    }
  }
  frame.leds_written = static_cast<uint32_t>(complete < grbw_.size() ? complete : grbw_.size());
  frame.bits_left = complete < grbw_.size() ? static_cast<uint32_t>(received_.size() % 32) : 0;
  frame.grbw = grbw_;
  frames_.push_back(std::move(frame));
  received_.clear();
}

std::vector<Sk6812Strip::Frame> Sk6812Strip::take_frames() {
  std::vector<Frame> out;
  out.swap(frames_);
  return out;
}

void ServoInput::level(bool high, uint64_t ps) {
  if (high == high_) return;
  if (ps < rise_ps_) ps = rise_ps_;  // never back in time
  high_ = high;
  if (high) {
    poll(ps);
    rise_ps_ = ps;
    return;
  }
  const uint32_t us = static_cast<uint32_t>((ps - rise_ps_ + 500000) / 1000000);
  ++pulses_;
  if (!active_ || us != last_us_) events_.push_back(Event{ps, us});
  active_ = true;
  last_us_ = us;
}

uint64_t ServoInput::release_due_ps() const {
  return active_ && !high_ ? rise_ps_ + kReleasePs : UINT64_MAX;
}

void ServoInput::poll(uint64_t now_ps) {
  if (release_due_ps() > now_ps) return;
  events_.push_back(Event{release_due_ps(), 0});
  active_ = false;
}

std::vector<ServoInput::Event> ServoInput::take_events() {
  std::vector<Event> out;
  out.swap(events_);
  return out;
}

}  // namespace hmc::emu
