// Host codec throughput: encode + decode of the same 10^6 frames by libhmc (encode_into, decode)
// and by a straightforward codec of the shape of the seed firmware's parser (split the line at
// every '#' into strings, stoi each field, sum the values; frames built with to_string and +),
// side by side in one run, with heap allocations per frame counted for both.
//
//   scripts/bench codec [--frames N] [--rounds R]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <string>
#include <vector>

#include "hmc/codec.h"

namespace {

size_t g_allocations = 0;

}  // namespace

void* operator new(std::size_t size) {
  ++g_allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace {

// The straightforward codec: what a first version, or the seed firmware's parser on a PC, does.
struct Straightforward {
  static std::string encode(const hmc::Command& command) {
    const hmc::CommandValues v = hmc::command_values(command);
    std::string frame = "STX#" + std::to_string(v.count + 1) + "#" + hmc::command_spec(command).name;
    uint32_t sum = 0;
    for (uint32_t i = 0; i < v.count; ++i) {
      frame += "#" + std::to_string(v.values[i]);
      sum += v.values[i];
    }
    return frame + "#" + std::to_string(sum % 256) + "#ETX";
  }
  // Returns false for a frame it refuses.
  static bool decode(const std::string& line, hmc::Command& out) {
    std::vector<std::string> fields;
    std::string field;
    for (const char c : line) {
      if (c == '#') {
        fields.push_back(field);
        field.clear();
      } else {
        field += c;
      }
    }
    fields.push_back(field);
    if (fields.size() < 5 || fields.front() != "STX" || fields.back() != "ETX") return false;
    const int length = std::stoi(fields[1]);
    if (length != static_cast<int>(fields.size()) - 4) return false;
    const hmc::proto::CommandSpec* spec = hmc::find_command(fields[2]);
    if (spec == nullptr || spec->value_count + 1u != static_cast<uint32_t>(length)) return false;
    uint32_t values[hmc::proto::kMaxValues] = {};
    uint32_t sum = 0;
    for (uint32_t i = 0; i < spec->value_count; ++i) {
      values[i] = static_cast<uint32_t>(std::stoi(fields[3 + i]));
      sum += values[i];
    }
    if (static_cast<uint32_t>(std::stoi(fields[fields.size() - 2])) != sum % 256) return false;
    out = hmc::make_command(spec->id, values);
    return true;
  }
};

std::vector<hmc::Command> frames(size_t n) {
  std::vector<hmc::Command> out;
  out.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const auto k = static_cast<uint32_t>(i);
    switch (i % 3) {
      case 0: out.push_back(hmc::StepperMove{1 + k % 3, 1 + k % 2, 1u << (k % 9), 1 + k % 100000, 100 + k % 3000}); break;
      case 1: out.push_back(hmc::ServoMove{1 + k % 2, 10 + k % 161}); break;
      default: out.push_back(hmc::LedColor{1 + k % 2, k % 256, (k / 3) % 256, (k / 7) % 256, (k / 11) % 256}); break;
    }
  }
  return out;
}

struct Figures {
  double seconds = 0;
  size_t allocations = 0;
  size_t checksum = 0;  // keeps the work from being optimised away, and must match
};

// Runs `body` over commands[first, last), timed.
template <typename Body>
Figures measure(const std::vector<hmc::Command>& commands, size_t first, size_t last, Body body) {
  Figures f;
  const size_t before = g_allocations;
  const auto start = std::chrono::steady_clock::now();
  for (size_t i = first; i < last; ++i) f.checksum += body(commands[i]);
  f.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  f.allocations = g_allocations - before;
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  size_t n = 1000000;
  int rounds = 5;
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::string(argv[i]) == "--frames") n = std::strtoul(argv[i + 1], nullptr, 10);
    if (std::string(argv[i]) == "--rounds") rounds = std::atoi(argv[i + 1]);
  }
  if (rounds < 1) rounds = 1;
  const std::vector<hmc::Command> commands = frames(n);

  // The two codecs take turns on each slice of 10 000 frames, round after round, and each keeps
  // its fastest time for every slice: whatever else the machine does in a moment slows both
  // alike, and a slow moment costs a codec that slice of one round, not its whole round.
  hmc::FrameText text;
  const auto ours_codec = [&](const hmc::Command& c) -> size_t {
    if (!hmc::encode_into(c, text)) return 0;
    const auto decoded = hmc::decode(text.view());
    return decoded && decoded->command == c ? text.size : 0;
  };
  const auto plain_codec = [&](const hmc::Command& c) -> size_t {
    const std::string frame = Straightforward::encode(c);
    hmc::Command back;
    return Straightforward::decode(frame, back) && back == c ? frame.size() : 0;
  };
  constexpr size_t kSlice = 10000;
  const size_t slices = (n + kSlice - 1) / kSlice;
  std::vector<double> ours_best(slices), plain_best(slices);
  Figures ours;
  Figures plain;
  for (int round = 0; round < rounds; ++round) {
    for (size_t k = 0; k < slices; ++k) {
      const size_t first = k * kSlice, last = std::min(n, first + kSlice);
      const Figures o = measure(commands, first, last, ours_codec);
      const Figures p = measure(commands, first, last, plain_codec);
      ours_best[k] = round == 0 ? o.seconds : std::min(ours_best[k], o.seconds);
      plain_best[k] = round == 0 ? p.seconds : std::min(plain_best[k], p.seconds);
      if (round == 0) {  // the same in every round
        ours.checksum += o.checksum;
        ours.allocations += o.allocations;
        plain.checksum += p.checksum;
        plain.allocations += p.allocations;
      }
    }
  }
  for (size_t k = 0; k < slices; ++k) {
    ours.seconds += ours_best[k];
    plain.seconds += plain_best[k];
  }
  if (ours.checksum != plain.checksum) {
    std::fprintf(stderr, "codec_bench: the two codecs disagree (%zu vs %zu bytes)\n", ours.checksum, plain.checksum);
    return 1;
  }
  const auto per = [&](const Figures& f) { return f.seconds / static_cast<double>(n) * 1e9; };
  std::printf("%zu frames (STM, SVM, LED), encoded then decoded, %zu bytes in all; each slice of 10 000 frames the "
              "fastest of %d rounds\n",
              n, ours.checksum, rounds);
  std::printf("  libhmc           %7.1f ns/frame  %6.2f M frames/s  %.2f allocations/frame\n", per(ours),
              1e-6 * static_cast<double>(n) / ours.seconds, static_cast<double>(ours.allocations) / static_cast<double>(n));
  std::printf("  split-and-stoi   %7.1f ns/frame  %6.2f M frames/s  %.2f allocations/frame\n", per(plain),
              1e-6 * static_cast<double>(n) / plain.seconds, static_cast<double>(plain.allocations) / static_cast<double>(n));
  std::printf("  libhmc is %.1fx faster\n", plain.seconds / ours.seconds);
  std::printf("summary: | host codec, encode + decode | %.0f ns/frame, %.2f allocations | %.0f ns/frame, %.2f allocations | "
              "%.1fx | >= 10x, no allocation per frame |\n",
              per(ours), static_cast<double>(ours.allocations) / static_cast<double>(n), per(plain),
              static_cast<double>(plain.allocations) / static_cast<double>(n), plain.seconds / ours.seconds);
  return 0;
}
