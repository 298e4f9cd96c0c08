// Corruption soak: how often does line noise turn a valid frame into a different valid one?
//
// Feeds the firmware's FrameParser::parse_line valid random frames (a mix of every command,
// random valid values) after one corruption each, and counts the frames it ACCEPTS as a
// command other than the one sent (an undetected error), per corruption class, with the seed's
// sum and with CRC-16 checksums. Every mode sees the same frames and the same corruptions.
//
// In CRC-16 mode the checksum field is always exactly five digits (docs/protocol.md "CRC-16
// mode"): the encoder pads, the parser refuses other widths, so a digit moved across the '#'
// before the checksum field, which the CRC does not cover, is caught.
// A benchmark, not a unit test: docs/performance.md has the figures and the command.
//
// Usage: corruption_soak [--frames N] [--seed S] [--markdown]
#include <chrono>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "core/frame_parser.h"
#include "hmc/codec.h"

namespace {

namespace proto = hmc::proto;
using proto::ChecksumMode;

// splitmix64: small, fast and the same on every compiler and library, so a seed reproduces
// the same frames everywhere (std:: distributions are implementation-defined).
class Random {
 public:
  explicit Random(uint64_t seed) : state_(seed) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [lo, hi]; the modulo bias is below 2^-32 for these ranges.
  uint32_t in(uint32_t lo, uint32_t hi) {
    return lo + static_cast<uint32_t>(next() % (static_cast<uint64_t>(hi) - lo + 1));
  }

 private:
  uint64_t state_;
};

uint32_t digits_of(uint32_t v) {
  uint32_t d = 1;
  while (v >= 10) v /= 10, ++d;
  return d;
}

// A value in [lo, hi] whose digit count is uniform over the range's: frames carry short and
// long numbers alike, as real ones do (3, 128, 1000, 409600).
uint32_t number_in(Random& random, uint32_t lo, uint32_t hi) {
  const uint32_t digits = random.in(digits_of(lo), digits_of(hi));
  uint64_t floor = 1;
  for (uint32_t i = 1; i < digits; ++i) floor *= 10;
  const uint64_t a = digits == 1 ? 0 : floor;
  const uint64_t b = floor * 10 - 1;
  const uint32_t from = static_cast<uint32_t>(a > lo ? a : lo);
  const uint32_t to = static_cast<uint32_t>(b < hi ? b : hi);
  return random.in(from, to);
}

// A random valid command. The mix weighs motion commands most, as a session does.
hmc::Command random_command(Random& random) {
  const uint32_t pick = random.in(0, 99);
  if (pick < 30) {
    hmc::StepperMove m;
    m.dir = random.in(0, 3);
    m.motor = m.dir == proto::kActionHome ? random.in(1, 2) : random.in(1, proto::kMotorCount);
    m.microstep = 1u << random.in(0, 8);
    m.steps = number_in(random, 0, proto::kIntMax);
    m.delay_us = number_in(random, 1, 100000);
    return m;
  }
  if (pick < 45) return hmc::ServoMove{random.in(1, proto::kServoCount), random.in(10, 170)};
  if (pick < 60) {
    return hmc::LedColor{random.in(1, proto::kStripCount), random.in(0, 255), random.in(0, 255), random.in(0, 255),
                         random.in(0, 255)};
  }
  if (pick < 75) {
    const uint32_t setting = random.in(1, proto::kSettingCount);
    const proto::SettingSpec& s = proto::kSettings[setting - 1];
    return hmc::SetSetting{random.in(1, proto::kMotorCount), setting, number_in(random, s.min, s.max)};
  }
  if (pick < 80) return hmc::GetSetting{random.in(1, proto::kMotorCount), random.in(1, proto::kSettingCount)};
  if (pick < 85) return hmc::StatusQuery{random.in(1, proto::kUnitFirstStrip + proto::kStripCount - 1)};
  if (pick < 95) {
    return hmc::SoftLimits{random.in(1, proto::kMotorCount), random.in(0, 1), number_in(random, 0, 1u << 24),
                           random.in(0, 1), number_in(random, 0, 1u << 24)};
  }
  if (pick < 98) return hmc::ChecksumModeCommand{random.in(0, 1)};
  return hmc::VersionQuery{};
}

enum class Corruption { kOnePrintable, kOneAny, kTwoPrintable, kTransposition, kBurst4 };
struct CorruptionClass {
  Corruption kind;
  const char* name;
};
constexpr CorruptionClass kClasses[] = {
    {Corruption::kOnePrintable, "1 byte replaced ('!'..'~')"},
    {Corruption::kOneAny, "1 byte replaced (any byte)"},
    {Corruption::kTwoPrintable, "2 bytes replaced ('!'..'~')"},
    {Corruption::kTransposition, "2 adjacent bytes swapped"},
    {Corruption::kBurst4, "4-byte burst ('!'..'~')"},
};
constexpr std::size_t kClassCount = sizeof(kClasses) / sizeof(kClasses[0]);

// A printable frame byte other than `old`.
char other_printable(Random& random, char old) {
  char c = old;
  while (c == old) c = static_cast<char>(random.in('!', '~'));
  return c;
}

char other_byte(Random& random, char old) {
  char c = old;
  while (c == old) c = static_cast<char>(random.in(0, 255));
  return c;
}

// Damages `frame` in place; every class changes at least one byte.
void corrupt(std::string& frame, Corruption kind, Random& random) {
  const auto last = static_cast<uint32_t>(frame.size() - 1);
  switch (kind) {
    case Corruption::kOnePrintable: {
      const uint32_t at = random.in(0, last);
      frame[at] = other_printable(random, frame[at]);
      break;
    }
    case Corruption::kOneAny: {
      const uint32_t at = random.in(0, last);
      frame[at] = other_byte(random, frame[at]);
      break;
    }
    case Corruption::kTwoPrintable: {
      const uint32_t a = random.in(0, last);
      uint32_t b = a;
      while (b == a) b = random.in(0, last);
      frame[a] = other_printable(random, frame[a]);
      frame[b] = other_printable(random, frame[b]);
      break;
    }
    case Corruption::kTransposition: {
      uint32_t at = 0;
      do {
        at = random.in(0, last - 1);
      } while (frame[at] == frame[at + 1]);  // swapping equal bytes changes nothing
      std::swap(frame[at], frame[at + 1]);
      break;
    }
    case Corruption::kBurst4: {
      const uint32_t at = random.in(0, last - 3);
      for (uint32_t i = at; i < at + 4; ++i) frame[i] = other_printable(random, frame[i]);
      break;
    }
  }
}

struct Tally {
  uint64_t frames = 0;
  uint64_t refused = 0;
  uint64_t accepted_same = 0;  // damage the command survived unchanged
  uint64_t undetected = 0;     // accepted as a different command
  std::string example;         // the first undetected error: sent -> received
};

bool same_command(const hmc::fw::Command& got, const hmc::Command& sent) {
  if (got.id != hmc::command_id(sent)) return false;
  uint32_t values[proto::kMaxValues] = {};
  const uint32_t count = hmc::fw::command_values(got, values);
  const hmc::CommandValues want = hmc::command_values(sent);
  if (count != want.count) return false;
  for (uint32_t i = 0; i < count; ++i) {
    if (values[i] != want.values[i]) return false;
  }
  return true;
}

struct Options {
  uint64_t frames = 1000000;
  uint64_t seed = 0x50AC0FFEE2024ull;
  bool markdown = false;
};

// The modes measured: the parser's two.
struct Mode {
  ChecksumMode parser_mode;
  const char* name;
};
constexpr Mode kModes[] = {
    {ChecksumMode::kSum, "sum"},
    {ChecksumMode::kCrc16, "CRC-16"},
};
constexpr std::size_t kModeCount = sizeof(kModes) / sizeof(kModes[0]);

bool parse_options(int argc, char** argv, Options& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--frames" && i + 1 < argc) {
      o.frames = std::strtoull(argv[++i], nullptr, 0);
    } else if (arg == "--seed" && i + 1 < argc) {
      o.seed = std::strtoull(argv[++i], nullptr, 0);
    } else if (arg == "--markdown") {
      o.markdown = true;
    } else {
      return false;
    }
  }
  return o.frames > 0;
}

std::string rate_text(uint64_t count, uint64_t frames) {
  char text[32];
  if (count == 0) {
    // With none seen in n trials, the rate is below 3/n with 95% confidence.
    std::snprintf(text, sizeof text, "(< %.0e)", 3.0 / static_cast<double>(frames));
  } else {
    std::snprintf(text, sizeof text, "%.2e", static_cast<double>(count) / static_cast<double>(frames));
  }
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parse_options(argc, argv, o)) {
    std::fprintf(stderr, "usage: corruption_soak [--frames N] [--seed S] [--markdown]\n");
    return 2;
  }
  const auto start = std::chrono::steady_clock::now();
  Tally tallies[kClassCount][kModeCount];
  uint64_t clean_refused = 0;

  for (std::size_t c = 0; c < kClassCount; ++c) {
    // Each class draws its own stream from the seed, the same in every mode.
    for (std::size_t m = 0; m < kModeCount; ++m) {
      const Mode& mode = kModes[m];
      Random random(o.seed + c);
      Tally& t = tallies[c][m];
      for (uint64_t n = 0; n < o.frames; ++n) {
        const hmc::Command sent = random_command(random);
        const std::string frame = hmc::encode(sent, mode.parser_mode).value();
        hmc::fw::Verdict verdict{};
        if (n % 64 == 0) {  // the clean frame must pass, or the soak measures nothing
          hmc::fw::FrameParser::parse_line(reinterpret_cast<const uint8_t*>(frame.data()),
                                           static_cast<uint32_t>(frame.size()), verdict, mode.parser_mode);
          clean_refused += verdict.reason != proto::Reason::kOk || !same_command(verdict.command, sent);
        }
        std::string damaged = frame;
        corrupt(damaged, kClasses[c].kind, random);
        ++t.frames;
        const bool judged = hmc::fw::FrameParser::parse_line(reinterpret_cast<const uint8_t*>(damaged.data()),
                                                             static_cast<uint32_t>(damaged.size()), verdict,
                                                             mode.parser_mode);
        if (!judged || verdict.reason != proto::Reason::kOk) {
          ++t.refused;
        } else if (same_command(verdict.command, sent)) {
          ++t.accepted_same;
        } else {
          ++t.undetected;
          if (t.example.empty()) t.example = frame + " -> " + damaged;
        }
      }
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::printf("corruption soak: %" PRIu64 " frames per class and mode, seed 0x%" PRIX64
              ", FrameParser::parse_line, %.1f s\n\n",
              o.frames, o.seed, seconds);
  std::printf("undetected errors (accepted as another command), count and rate:\n\n");
  if (o.markdown) {
    std::printf("| corruption |");
    for (const Mode& mode : kModes) std::printf(" %s |", mode.name);
    std::printf("\n|---|");
    for (std::size_t m = 0; m < kModeCount; ++m) std::printf("---|");
    std::printf("\n");
  } else {
    std::printf("%-30s", "corruption");
    for (const Mode& mode : kModes) std::printf(" %24s", mode.name);
    std::printf("\n");
  }
  for (std::size_t c = 0; c < kClassCount; ++c) {
    std::printf(o.markdown ? "| %s |" : "%-30s", kClasses[c].name);
    for (std::size_t m = 0; m < kModeCount; ++m) {
      const Tally& t = tallies[c][m];
      const std::string cell = std::to_string(t.undetected) + (t.undetected == 0 ? "" : " = ") +
                               (t.undetected == 0 ? " " + rate_text(0, t.frames) : rate_text(t.undetected, t.frames));
      std::printf(o.markdown ? " %s |" : " %24s", cell.c_str());
    }
    std::printf("\n");
  }
  std::printf("\nexamples of undetected errors (sent -> accepted):\n");
  for (std::size_t c = 0; c < kClassCount; ++c) {
    for (std::size_t m = 0; m < kModeCount; ++m) {
      if (tallies[c][m].example.empty()) continue;
      std::printf("  %s, %s: %s\n", kClasses[c].name, kModes[m].name, tallies[c][m].example.c_str());
    }
  }
  uint64_t same = 0;
  for (const auto& row : tallies) {
    for (const Tally& t : row) same += t.accepted_same;
  }
  std::printf("accepted unchanged (harmless damage): %" PRIu64 "; clean frames refused: %" PRIu64 "\n", same,
              clean_refused);
  // One line for the summary table: every class together, CRC-16 beside the seed's sum.
  uint64_t undetected[kModeCount] = {};
  uint64_t damaged = 0;
  for (std::size_t c = 0; c < kClassCount; ++c) {
    damaged += tallies[c][0].frames;
    for (std::size_t m = 0; m < kModeCount; ++m) undetected[m] += tallies[c][m].undetected;
  }
  std::printf("summary: | corruption soak, %" PRIu64 " damaged frames in %zu classes | CRC-16: %" PRIu64
              " accepted as another command | sum: %" PRIu64 " | %s | CRC-16 catches what the sum misses |\n",
              damaged, kClassCount, undetected[1], undetected[0],
              undetected[1] == 0 ? "none get through" : (std::to_string(undetected[0] / undetected[1]) + "x fewer").c_str());
  return clean_refused == 0 ? 0 : 1;
}
