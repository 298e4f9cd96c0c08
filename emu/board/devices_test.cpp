// The pin devices (devices.h) on waveforms built here, and TCC0's waveform output reaching a
// servo pin through PORT on the emulated chip (timers.h, port.h, board.h).
#include <catch2/catch.hpp>

#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "../../firmware/targets/samd21/sk6812.h"
#include "board/board.h"
#include "board/samd21_board_map.h"
#include "board/devices.h"
#include "board/trace.h"
#include "chip/chip.h"
#include "chip/port.h"

namespace {

using hmc::emu::ServoInput;
using hmc::emu::Sk6812Strip;

constexpr uint64_t kUs = 1000000;  // ps
// 2.4 MHz SPI: a bit every 416 666.7 ps; the SERCOM model's bit time rounds to whole ps.
constexpr uint64_t kSpiBitPs = 416666;

// Feeds SPI bytes to a strip as the SERCOM puts them on the data pin, MSB first, back to back.
uint64_t send(Sk6812Strip& strip, const std::vector<uint8_t>& bytes, uint64_t at) {
  for (const uint8_t byte : bytes) {
    for (int bit = 7; bit >= 0; --bit) {
      strip.level(((byte >> bit) & 1) != 0, at);
      at += kSpiBitPs;
    }
  }
  return at;
}

std::vector<uint8_t> encode(unsigned leds, uint8_t r, uint8_t g, uint8_t b, uint8_t w) {
  std::vector<uint8_t> out;
  uint8_t led[hmc::samd21::sk6812::kSpiBytesPerLed];
  hmc::samd21::sk6812::encode_led(r, g, b, w, led);
  for (unsigned i = 0; i < leds; ++i) out.insert(out.end(), led, led + sizeof led);
  return out;
}

}  // namespace

TEST_CASE("an SK6812 strip decodes the image's SPI encoding into GRBW per LED") {
  Sk6812Strip strip(90);
  std::vector<uint8_t> bytes = encode(90, 255, 64, 0, 10);
  bytes.insert(bytes.end(), 90, 0);  // led_strips.h: 90 zero bytes, 300 us low, latch
  const uint64_t end = send(strip, bytes, 5 * kUs);
  strip.poll(end);
  const std::vector<Sk6812Strip::Frame> frames = strip.take_frames();
  REQUIRE(frames.size() == 1);
  CHECK(frames[0].leds_written == 90);
  CHECK(frames[0].bits_left == 0);
  for (const auto& led : frames[0].grbw) CHECK((led == std::array<uint8_t, 4>{64, 255, 0, 10}));
  // The latch falls 80 us after the last bit's falling edge.
  CHECK(frames[0].latched_ps > 5 * kUs + 1080 * 8 * kSpiBitPs);
  CHECK(frames[0].latched_ps < 5 * kUs + 1080 * 8 * kSpiBitPs + 81 * kUs);
  // Finding: a 1 sent as 110 at 2.4 MHz is high 0.83 us, outside T1H's 0.6 +- 0.15 us, and low
  // 0.42 us, outside T1L's 0.6 +- 0.15 us; a 0 (100: 0.42 us high, 0.83 us low) is inside both.
  // Every 1 bit of the frame: G 255 (8 ones), R 64 (1), W 10 (2) per LED.
  CHECK(strip.bits() == 90u * 32u);
  CHECK(strip.highs_off_window() == 90u * 11u);
}

TEST_CASE("an SK6812 strip latches only after 80 us low and keeps LEDs no bit reached") {
  Sk6812Strip strip(4);
  uint64_t at = send(strip, encode(4, 1, 2, 3, 4), 0);
  // 79 us low: no latch yet; the next bits continue the same frame (they go to LEDs 5.., off
  // the end of a 4-LED strip).
  strip.poll(at + 79 * kUs);
  CHECK(strip.take_frames().empty());
  at = send(strip, encode(1, 9, 9, 9, 9), at + 79 * kUs);
  strip.poll(at + 80 * kUs);
  std::vector<Sk6812Strip::Frame> frames = strip.take_frames();
  REQUIRE(frames.size() == 1);
  CHECK(frames[0].grbw[3] == (std::array<uint8_t, 4>{2, 1, 3, 4}));
  // Two LEDs' worth and half a byte: LEDs 0-1 change, 2-3 keep their colour, 4 bits left over.
  std::vector<uint8_t> partial = encode(2, 7, 7, 7, 7);
  partial.push_back(0xDA);  // 110 110 10: a 1, a 1, then a short high: a 0
  at = send(strip, partial, at + 100 * kUs);
  strip.poll(at + 100 * kUs);
  frames = strip.take_frames();
  REQUIRE(frames.size() == 1);
  CHECK(frames[0].leds_written == 2);
  CHECK(frames[0].bits_left == 3);
  CHECK(frames[0].grbw[1] == (std::array<uint8_t, 4>{7, 7, 7, 7}));
  CHECK(frames[0].grbw[2] == (std::array<uint8_t, 4>{2, 1, 3, 4}));
}

TEST_CASE("a servo input measures each pulse and notices the pulse train stop") {
  ServoInput servo;
  uint64_t at = 0;
  for (int i = 0; i < 3; ++i) {
    servo.level(true, at);
    servo.level(false, at + 1500 * kUs);
    at += 20000 * kUs;
  }
  servo.level(true, at);
  servo.level(false, at + 900 * kUs + 400000);  // 900.4 us: 900 to the nearest us
  servo.poll(at + 29999 * kUs);
  std::vector<ServoInput::Event> events = servo.take_events();
  REQUIRE(events.size() == 2);
  CHECK(events[0].pulse_us == 1500);
  CHECK(events[1].pulse_us == 900);
  CHECK(servo.release_due_ps() == at + ServoInput::kReleasePs);
  servo.poll(at + ServoInput::kReleasePs);
  events = servo.take_events();
  REQUIRE(events.size() == 1);
  CHECK(events[0].pulse_us == 0);
  CHECK(servo.pulses() == 4);
}

namespace {

hmc::emu::ChipOptions cold_reset() {
  hmc::emu::ChipOptions options;
  options.after_bootloader = false;  // generator 0 on OSC8M: 1 MHz after reset
  return options;
}

// The chip after a cold reset with TCC0 clocked from generator 0 (OSC8M / 8 = 1 MHz), counting
// at DIV1: one count per µs. The board's servo-1 events go to a trace read back as text.
struct TccBench {
  mutable hmc::emu::Chip chip{cold_reset()};
  std::ostringstream out;
  hmc::emu::Trace trace{out};
  TccBench() {
    chip.bus_write(0x40000420, chip.bus_read(0x40000420, 4) | (1u << 8), 4);  // PM APBCMASK: TCC0
    chip.bus_write(0x40000C02, 0x4000 | 0x1A, 2);  // GCLK CLKCTRL: CLKEN, GEN 0, ID TCC0_TCC1
    chip.board().set_trace(&trace);
  }
  void tcc(uint32_t offset, uint32_t value) { chip.bus_write(0x42002000 + offset, value, 4); }
  // The servo-1 pin (board.h) handed to TCC0 by its PMUX function, as pin_function() does.
  void hand_over_servo1() {
    namespace pinmap = hmc::samd21::board;
    const pinmap::Pin pin = pinmap::servo::kPins[0];
    const uint32_t pmux = 0x41004400u + 0x80u * pin.group + 0x30u + pin.number / 2u;
    const uint32_t shift = (pin.number & 1) != 0 ? 4 : 0;
    const uint32_t function = static_cast<uint32_t>(pinmap::servo::kFunctions[0]);
    chip.bus_write(pmux, (chip.bus_read(pmux, 1) & ~(0xFu << shift)) | function << shift, 1);
    const uint32_t pincfg = 0x41004400u + 0x80u * pin.group + 0x40u + pin.number;
    chip.bus_write(pincfg, chip.bus_read(pincfg, 1) | 1, 1);  // PMUXEN
  }
  // Times from the enable on (the writes before it stall the bus for their synchronisation).
  uint64_t origin_ps = 0;
  void run_to_us(uint64_t us) {
    chip.charge_cycles(chip.cycles_at(origin_ps + us * kUs) - chip.cycles());
    chip.advance();
  }
  uint64_t pulses() const { return chip.board().servo(0).pulses(); }
  // The servo-1 widths the trace reports (each change).
  std::vector<int> widths() const {
    std::vector<int> w;
    std::istringstream in(out.str());
    for (std::string line; std::getline(in, line);) {
      const size_t at = line.find("\"servo\":1,\"pulse_us\":");
      if (at != std::string::npos) w.push_back(std::stoi(line.substr(at + 21)));
    }
    return w;
  }
};

}  // namespace

TEST_CASE("TCC0's NPWM output reaches a servo pin only through its PMUX function") {
  TccBench bench;
  REQUIRE(bench.chip.channel_hz(0x1A) == 1000000);
  const unsigned channel = hmc::samd21::board::servo::kChannels[0];
  bench.tcc(0x3C, 2);                   // WAVE: NPWM
  bench.tcc(0x40, 20000 - 1);           // PER: 20 ms
  bench.tcc(0x44 + 4 * channel, 1500);  // CC: 1.5 ms
  bench.origin_ps = bench.chip.now_ps();  // the counter starts at the enable write
  bench.tcc(0x00, 2);                   // ENABLE
  bench.run_to_us(50000);
  CHECK(bench.pulses() == 0);  // not handed over: nothing reaches the servo
  SECTION("handed over where the output is low: every pulse whole") {
    bench.run_to_us(60000 + 5000);  // 5 ms into a period, past the 1.5 ms pulse
    bench.hand_over_servo1();
    bench.run_to_us(130000);
    CHECK(bench.pulses() == 3);
    CHECK(bench.widths() == std::vector<int>{1500});
  }
  SECTION("handed over mid-pulse: the first pulse is short (what servo_pwm.h's hand-over avoids)") {
    bench.run_to_us(60000 + 1000);  // 1 ms into the 1.5 ms pulse
    bench.hand_over_servo1();
    bench.run_to_us(130000);
    CHECK(bench.pulses() == 4);
    CHECK(bench.widths() == std::vector<int>{500, 1500});
  }
  SECTION("CCB waits for the period's end; a CC written below the counter matches only next period") {
    bench.run_to_us(60000 + 5000);
    bench.hand_over_servo1();
    bench.tcc(0x70 + 4 * channel, 1000);  // CCB: 1 ms from the next period on
    bench.run_to_us(100000 + 5000);       // two periods
    CHECK(bench.widths() == std::vector<int>{1000});
    bench.tcc(0x44 + 4 * channel, 500);   // CC at once, 5 ms into the period: no match this period
    bench.run_to_us(140000 + 5000);
    CHECK(bench.widths() == std::vector<int>{1000, 500});
  }
  SECTION("a CC written below the counter mid-pulse stretches that pulse to the next period's match") {
    bench.run_to_us(60000 + 5000);
    bench.hand_over_servo1();
    bench.run_to_us(80000 + 1000);        // 1 ms into a pulse
    bench.tcc(0x44 + 4 * channel, 500);   // below the counter: the output stays high
    bench.run_to_us(120000 + 5000);
    CHECK(bench.widths() == std::vector<int>{20500, 500});
  }
}
