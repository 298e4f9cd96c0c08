// How a conformance vector's `input` string holds bytes (conformance/README.md): each code
// point U+0000..U+00FF of the JSON string is one byte. Shared by the conformance runner and the
// fuzzers' seed-corpus writer.
#pragma once

#include <stdexcept>
#include <string>

namespace hmc::conformance {

// The bytes a vector's input stands for; throws on a code point above U+00FF.
inline std::string input_bytes(const std::string& utf8) {
  std::string out;
  for (std::size_t i = 0; i < utf8.size(); ++i) {
    const auto c = static_cast<unsigned char>(utf8[i]);
    if (c < 0x80) {
      out += static_cast<char>(c);
    } else if (c >= 0xC2 && c <= 0xC3 && i + 1 < utf8.size()) {
      const auto next = static_cast<unsigned char>(utf8[++i]);
      out += static_cast<char>(((c & 0x1Fu) << 6) | (next & 0x3Fu));
    } else {
      throw std::runtime_error("vector input has a code point above U+00FF");
    }
  }
  return out;
}

}  // namespace hmc::conformance
