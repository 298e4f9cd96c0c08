// Shared by the fuzz targets: one verdict shape for both parsers, so they compare field by
// field and print the same way, plus byte escaping and a check that aborts with a message.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "core/frame_parser.h"
#include "hmc/codec.h"
#include "hmc/command.h"

namespace hmc::fuzz {

// Bytes as a C-style string literal body: printable ASCII as is, everything else escaped.
inline std::string escape(std::string_view bytes) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  for (char byte : bytes) {
    const auto c = static_cast<unsigned char>(byte);
    switch (c) {
      case '\r': out += "\\r"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '\\': out += "\\\\"; break;
      case '"': out += "\\\""; break;
      default:
        if (c >= 0x20 && c < 0x7F) {
          out += static_cast<char>(c);
        } else {
          out += "\\x";
          out += kHex[c >> 4];
          out += kHex[c & 0xF];
        }
    }
  }
  return out;
}

inline std::string_view as_text(const uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// Prints what went wrong, with the input that did it, and aborts so the fuzzer keeps the input.
[[noreturn]] inline void fail(const std::string& what, std::string_view input) {
  std::fprintf(stderr, "\n==== invariant violated: %s\n     input (%zu bytes): \"%s\"\n", what.c_str(),
               input.size(), escape(input).c_str());
  std::fflush(stderr);
  std::abort();
}

// Fails unless `holds`; `explain` builds the message only then, as checks run on every byte.
template <typename Explain>
void require(bool holds, Explain&& explain, std::string_view input) {
  if (!holds) fail(explain(), input);
}

// A command as its id and its values in wire order.
struct Values {
  proto::CommandId id = proto::CommandId::kStepper;
  uint32_t count = 0;
  uint32_t v[proto::kMaxValues] = {};
};

inline Values values_of(const fw::Command& c) {
  Values out;
  out.id = c.id;
  out.count = fw::command_values(c, out.v);
  return out;
}

inline Values values_of(const Command& c) {
  const CommandValues cv = command_values(c);
  Values out;
  out.id = command_id(c);
  out.count = cv.count;
  for (uint32_t i = 0; i < cv.count; ++i) out.v[i] = cv.values[i];
  return out;
}

inline bool same_values(const Values& a, const Values& b) {
  if (a.id != b.id || a.count != b.count) return false;
  for (uint32_t i = 0; i < a.count; ++i) {
    if (a.v[i] != b.v[i]) return false;
  }
  return true;
}

inline std::string to_string(const Values& c) {
  const proto::CommandSpec& spec = proto::command_spec(c.id);
  std::string out = spec.name;
  for (uint32_t i = 0; i < c.count; ++i) {
    out += ' ';
    out += i < spec.value_count ? spec.fields[i].name : "?";
    out += '=' + std::to_string(c.v[i]);
  }
  return out;
}

// One line's verdict in terms both parsers share. `token` is -1 for none.
struct Outcome {
  enum class Kind { kIgnored, kAccepted, kRefused };
  Kind kind = Kind::kIgnored;
  proto::Reason reason = proto::Reason::kOk;
  int token = 0;
  std::size_t offset = 0;
  uint32_t expected = 0;
  uint32_t found = 0;
  Values command;  // accepted only
};

inline Outcome outcome_of(const fw::Verdict& v) {
  Outcome out;
  if (v.reason == proto::Reason::kOk) {
    out.kind = Outcome::Kind::kAccepted;
    out.command = values_of(v.command);
    return out;
  }
  out.kind = Outcome::Kind::kRefused;
  out.reason = v.reason;
  out.token = v.token == proto::kNoToken ? -1 : v.token;
  out.offset = v.offset;
  out.expected = v.expected;
  out.found = v.found;
  return out;
}

inline Outcome outcome_of(const Result<Decoded, Diagnostic>& r) {
  Outcome out;
  if (r) {
    out.kind = Outcome::Kind::kAccepted;
    out.command = values_of(r->command);
    return out;
  }
  const Diagnostic& d = r.error();
  out.kind = Outcome::Kind::kRefused;
  out.reason = d.reason;
  out.token = d.token == kNoToken ? -1 : d.token;
  out.offset = d.offset;
  out.expected = d.expected;
  out.found = d.found;
  return out;
}

inline bool operator==(const Outcome& a, const Outcome& b) {
  if (a.kind != b.kind) return false;
  switch (a.kind) {
    case Outcome::Kind::kIgnored: return true;
    case Outcome::Kind::kAccepted: return same_values(a.command, b.command);
    case Outcome::Kind::kRefused:
      return a.reason == b.reason && a.token == b.token && a.offset == b.offset && a.expected == b.expected &&
             a.found == b.found;
  }
  return false;
}
inline bool operator!=(const Outcome& a, const Outcome& b) { return !(a == b); }

inline std::string to_string(const Outcome& o) {
  switch (o.kind) {
    case Outcome::Kind::kIgnored: return "ignored";
    case Outcome::Kind::kAccepted: return "accepted " + to_string(o.command);
    case Outcome::Kind::kRefused:
      return std::string("refused ") + proto::reason_spec(o.reason).name +
             " token=" + (o.token < 0 ? std::string("none") : std::to_string(o.token)) +
             " offset=" + std::to_string(o.offset) + " expected=" + std::to_string(o.expected) +
             " found=" + std::to_string(o.found);
  }
  return "?";
}

inline std::string to_string(const std::vector<Outcome>& list) {
  std::string out;
  for (std::size_t i = 0; i < list.size(); ++i) out += "\n       [" + std::to_string(i) + "] " + to_string(list[i]);
  return list.empty() ? "\n       (no verdicts)" : out;
}

}  // namespace hmc::fuzz
