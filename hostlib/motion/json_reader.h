// A small JSON reader that remembers where every value and key is (line, column, byte span), so
// a validator can point at the exact spot of a mistake. Internal to the host library (motion
// files use it); RFC 8259 JSON in UTF-8, numbers as double, plus `//` and `/* */` comments
// (choreographies want them). A trailing comma is refused with a message that says so.
//
// Nesting is limited (kMaxDepth) so hostile input cannot exhaust the stack. A duplicate key in an
// object is not a syntax error: it is reported in Document::duplicates and the first value is
// kept, so a validator can go on and report everything else too.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "hmc/result.h"

namespace hmc::json {

inline constexpr int kMaxDepth = 64;

struct Position {
  uint32_t line = 1;    // 1-based
  uint32_t column = 1;  // 1-based, in bytes
  size_t offset = 0;    // byte offset in the text
};

struct Member;

struct Value {
  enum class Kind : uint8_t { kNull, kBool, kNumber, kString, kArray, kObject };
  Kind kind = Kind::kNull;
  Position at;     // its first byte
  size_t end = 0;  // one past its last byte
  bool boolean = false;
  double number = 0;
  std::string string;          // kString: the decoded text
  std::vector<Value> items;    // kArray
  std::vector<Member> members;  // kObject, in file order, no two with the same key

  const Member* find(std::string_view key) const;
  bool is(Kind k) const { return kind == k; }
};

struct Member {
  std::string key;  // decoded
  Position at;      // the key's opening quote
  size_t end = 0;   // one past the key's closing quote
  Value value;
};

// A syntax error, or a duplicate key.
struct Problem {
  Position at;
  std::string path;      // JSON path of the value being read: "$.steps[3].move"
  std::string expected;  // "',' or '}'"
  std::string found;     // the text there, shortened, or "end of file"
  std::string message;
};

struct Document {
  Value root;
  std::vector<Problem> duplicates;
};

// Reads one JSON value filling all of `text` (blanks around it and a leading byte-order mark
// allowed). A syntax error stops the reading: it is the one error returned.
Result<Document, Problem> read(std::string_view text);

// A path with one more object key: `.key` for plain names, `["key"]` for anything else.
std::string path_with_key(const std::string& path, std::string_view key);
// A path with one more array index: `[i]`.
std::string path_with_index(const std::string& path, size_t index);
// The text from `begin` to `end` for messages: blank runs as one space, at most `max` bytes
// (cut on a character boundary, "..." appended).
std::string excerpt(std::string_view text, size_t begin, size_t end, size_t max = 40);

}  // namespace hmc::json
