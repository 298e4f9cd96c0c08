// The position-keeping JSON reader (json_reader.h): recursive descent over the text, one
// function per grammar rule, tracking line and column as it goes.
#include "json_reader.h"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <limits>
#include <optional>
#include <system_error>
#include <unordered_set>
#include <utility>

namespace hmc::json {

namespace {

// Length of the well-formed UTF-8 sequence at text[i], or 0 when it is not one (overlong
// forms, surrogates and code points above U+10FFFF are not).
size_t utf8_length(std::string_view text, size_t i) {
  const auto byte = [&](size_t k) { return i + k < text.size() ? static_cast<unsigned char>(text[i + k]) : 0u; };
  const unsigned b0 = byte(0);
  if (b0 < 0x80) return 1;
  const auto cont = [&](size_t k, unsigned lo = 0x80, unsigned hi = 0xBF) {
    const unsigned b = byte(k);
    return b >= lo && b <= hi;
  };
  if (b0 >= 0xC2 && b0 <= 0xDF) return cont(1) ? 2 : 0;
  if (b0 == 0xE0) return cont(1, 0xA0) && cont(2) ? 3 : 0;
  if (b0 == 0xED) return cont(1, 0x80, 0x9F) && cont(2) ? 3 : 0;
  if (b0 >= 0xE1 && b0 <= 0xEF) return cont(1) && cont(2) ? 3 : 0;
  if (b0 == 0xF0) return cont(1, 0x90) && cont(2) && cont(3) ? 4 : 0;
  if (b0 >= 0xF1 && b0 <= 0xF3) return cont(1) && cont(2) && cont(3) ? 4 : 0;
  if (b0 == 0xF4) return cont(1, 0x80, 0x8F) && cont(2) && cont(3) ? 4 : 0;
  return 0;
}

void append_utf8(std::string& out, uint32_t cp) {
  if (cp < 0x80) {
    out += static_cast<char>(cp);
  } else if (cp < 0x800) {
    out += static_cast<char>(0xC0 | (cp >> 6));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else if (cp < 0x10000) {
    out += static_cast<char>(0xE0 | (cp >> 12));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else {
    out += static_cast<char>(0xF0 | (cp >> 18));
    out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  }
}

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }
bool is_digit(char c) { return c >= '0' && c <= '9'; }

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool is_plain_name(std::string_view key) {
  if (key.empty() || is_digit(key[0])) return false;
  for (char c : key) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || is_digit(c) || c == '_' || c == '-';
    if (!ok) return false;
  }
  return true;
}

uint32_t clamp32(size_t v) {
  return v > std::numeric_limits<uint32_t>::max() ? std::numeric_limits<uint32_t>::max() : static_cast<uint32_t>(v);
}

class Reader {
 public:
  explicit Reader(std::string_view text) : text_(text) {}

  Result<Document, Problem> run() {
    // A byte-order mark is not JSON, but editors write one; it is skipped, not counted.
    if (text_.substr(0, 3) == "\xEF\xBB\xBF") pos_ = line_start_ = 3;
    Document doc;
    skip_blanks();
    if (value(doc.root, 0)) {
      skip_blanks();
      if (pos_ != text_.size()) fail(here(), "the end of the file after the JSON value", "text after the JSON value");
    }
    if (error_) return std::move(*error_);
    doc.duplicates = std::move(duplicates_);
    return doc;
  }

 private:
  struct Segment {
    bool is_key = false;
    std::string key;
    size_t index = 0;
  };

  Position here() const { return {clamp32(line_), clamp32(pos_ - line_start_ + 1), pos_}; }
  bool at_end() const { return pos_ >= text_.size(); }
  char peek() const { return at_end() ? '\0' : text_[pos_]; }

  std::string path() const {
    std::string out = "$";
    for (const Segment& s : segments_) out = s.is_key ? path_with_key(out, s.key) : path_with_index(out, s.index);
    return out;
  }

  // Records the first syntax error; returns false so callers can `return fail(...)`.
  bool fail(Position at, std::string expected, std::string message) {
    if (error_) return false;
    Problem p;
    p.at = at;
    p.path = path();
    p.expected = std::move(expected);
    if (at.offset >= text_.size()) {
      p.found = "end of file";
    } else {
      size_t line_end = text_.find_first_of("\r\n", at.offset);
      if (line_end == std::string_view::npos) line_end = text_.size();
      p.found = excerpt(text_, at.offset, line_end, 20);
    }
    p.message = "invalid JSON: " + std::move(message);
    error_ = std::move(p);
    return false;
  }

  // Blanks and comments: `// to the end of the line` and `/* to the closing */`, which motion
  // files allow (choreographies want them) though JSON does not. A '/' that starts neither is
  // left for the caller to refuse as it would any other byte.
  void skip_blanks() {
    while (!at_end()) {
      const char c = text_[pos_];
      if (is_blank(c)) {
        advance();
      } else if (c == '/' && pos_ + 1 < text_.size() && text_[pos_ + 1] == '/') {
        while (!at_end() && text_[pos_] != '\n') advance();
      } else if (c == '/' && pos_ + 1 < text_.size() && text_[pos_ + 1] == '*') {
        const Position start = here();
        pos_ += 2;
        while (!at_end() && text_.substr(pos_, 2) != "*/") advance();
        if (at_end()) {
          fail(start, "'*/' closing the comment", "a comment opened with '/*' is never closed");
          return;
        }
        pos_ += 2;
      } else {
        return;
      }
    }
  }

  // One byte on, counting lines.
  void advance() {
    if (text_[pos_] == '\n') {
      ++line_;
      line_start_ = pos_ + 1;
    }
    ++pos_;
  }

  // After a ',' in an object or array: a closing bracket there is a trailing comma, which JSON
  // does not allow (though editors' own formats do), so it gets a message of its own. It is
  // reported where the missing value or key belongs, as any other missing one is.
  bool trailing_comma(const Position& comma, char close, const std::string& expected) {
    if (peek() != close) return false;
    fail(here(), expected,
         "trailing comma: the ',' at line " + std::to_string(comma.line) + ", column " + std::to_string(comma.column) +
             " is followed by '" + close + "'; remove it");
    return true;
  }

  bool value(Value& out, int depth) {
    out.at = here();
    bool ok = false;
    switch (peek()) {
      case '{': ok = object(out, depth + 1); break;
      case '[': ok = array(out, depth + 1); break;
      case '"':
        out.kind = Value::Kind::kString;
        ok = string(out.string);
        break;
      case 't': ok = literal("true", out, Value::Kind::kBool, true); break;
      case 'f': ok = literal("false", out, Value::Kind::kBool, false); break;
      case 'n': ok = literal("null", out, Value::Kind::kNull, false); break;
      default:
        if (peek() == '-' || is_digit(peek())) {
          ok = number(out);
        } else {
          return fail(here(), "a value (object, array, string, number, true, false or null)",
                      at_end() ? "the file ends where a value belongs" : "not a JSON value");
        }
    }
    out.end = pos_;
    return ok;
  }

  bool literal(std::string_view word, Value& out, Value::Kind kind, bool flag) {
    if (text_.substr(pos_, word.size()) != word) {
      return fail(here(), "a value (object, array, string, number, true, false or null)", "not a JSON value");
    }
    pos_ += word.size();
    out.kind = kind;
    out.boolean = flag;
    return true;
  }

  bool object(Value& out, int depth) {
    if (depth > kMaxDepth) return fail(here(), "at most 64 nested objects and arrays", "nested too deeply");
    out.kind = Value::Kind::kObject;
    ++pos_;  // '{'
    skip_blanks();
    if (peek() == '}') {
      ++pos_;
      return true;
    }
    std::unordered_set<std::string> keys;  // only for large objects, where a linear search would be slow
    for (;;) {
      skip_blanks();
      if (peek() != '"') return fail(here(), "a key in double quotes", "an object key must be a string");
      Member m;
      m.at = here();
      if (!string(m.key)) return false;
      m.end = pos_;
      skip_blanks();
      if (peek() != ':') return fail(here(), "':'", "a key must be followed by ':'");
      ++pos_;
      skip_blanks();
      segments_.push_back({true, m.key, 0});
      const bool ok = value(m.value, depth);
      segments_.pop_back();
      if (!ok) return false;

      const Member* first = nullptr;
      if (out.members.size() < 16) {
        first = out.find(m.key);
      } else {
        if (keys.empty()) {
          for (const Member& k : out.members) keys.insert(k.key);
        }
        if (!keys.insert(m.key).second) first = out.find(m.key);
      }
      if (first != nullptr) {
        Problem p;
        p.at = m.at;
        p.path = path_with_key(path(), m.key);
        p.expected = "each key once in an object";
        p.found = excerpt(text_, m.at.offset, m.end);
        p.message = "duplicate key " + p.found + " (first at line " + std::to_string(first->at.line) + ", column " +
                    std::to_string(first->at.column) + ")";
        duplicates_.push_back(std::move(p));
      } else {
        out.members.push_back(std::move(m));
      }

      skip_blanks();
      if (peek() == ',') {
        const Position comma = here();
        ++pos_;
        skip_blanks();
        if (trailing_comma(comma, '}', "a key in double quotes")) return false;
        continue;
      }
      if (peek() == '}') {
        ++pos_;
        return true;
      }
      return fail(here(), "',' or '}'", at_end() ? "the file ends inside an object" : "missing ',' or '}' in an object");
    }
  }

  bool array(Value& out, int depth) {
    if (depth > kMaxDepth) return fail(here(), "at most 64 nested objects and arrays", "nested too deeply");
    out.kind = Value::Kind::kArray;
    ++pos_;  // '['
    skip_blanks();
    if (peek() == ']') {
      ++pos_;
      return true;
    }
    for (;;) {
      skip_blanks();
      segments_.push_back({false, {}, out.items.size()});
      out.items.emplace_back();
      const bool ok = value(out.items.back(), depth);
      segments_.pop_back();
      if (!ok) return false;
      skip_blanks();
      if (peek() == ',') {
        const Position comma = here();
        ++pos_;
        skip_blanks();
        segments_.push_back({false, {}, out.items.size()});
        const bool trailing = trailing_comma(comma, ']', "a value (object, array, string, number, true, false or null)");
        segments_.pop_back();
        if (trailing) return false;
        continue;
      }
      if (peek() == ']') {
        ++pos_;
        return true;
      }
      return fail(here(), "',' or ']'", at_end() ? "the file ends inside an array" : "missing ',' or ']' in an array");
    }
  }

  std::optional<uint32_t> hex4() {
    if (pos_ + 4 > text_.size()) return std::nullopt;
    uint32_t v = 0;
    for (size_t i = 0; i < 4; ++i) {
      const int h = hex_value(text_[pos_ + i]);
      if (h < 0) return std::nullopt;
      v = v * 16 + static_cast<uint32_t>(h);
    }
    pos_ += 4;
    return v;
  }

  bool string(std::string& out) {
    const Position start = here();
    ++pos_;  // '"'
    for (;;) {
      if (at_end()) return fail(start, "a closing '\"'", "the string is not closed");
      const char c = text_[pos_];
      const auto u = static_cast<unsigned char>(c);
      if (c == '"') {
        ++pos_;
        return true;
      }
      if (u < 0x20) {
        return fail(here(), "a printable character (write control characters as \\n, \\t or \\u00XX)",
                    c == '\n' || c == '\r' ? "the string is not closed on its line" : "a control character in a string");
      }
      if (u >= 0x80) {
        const size_t n = utf8_length(text_, pos_);
        if (n == 0) return fail(here(), "UTF-8 text", "a byte that is not UTF-8");
        out.append(text_.substr(pos_, n));
        pos_ += n;
        continue;
      }
      if (c != '\\') {
        out += c;
        ++pos_;
        continue;
      }
      const Position escape = here();
      ++pos_;
      switch (peek()) {
        case '"': out += '"'; break;
        case '\\': out += '\\'; break;
        case '/': out += '/'; break;
        case 'b': out += '\b'; break;
        case 'f': out += '\f'; break;
        case 'n': out += '\n'; break;
        case 'r': out += '\r'; break;
        case 't': out += '\t'; break;
        case 'u': {
          ++pos_;
          const auto hi = hex4();
          if (!hi) return fail(escape, "\\u and four hex digits", "a broken \\u escape");
          uint32_t cp = *hi;
          if (cp >= 0xDC00 && cp <= 0xDFFF) return fail(escape, "a \\u escape of a character", "a lone low surrogate");
          if (cp >= 0xD800 && cp <= 0xDBFF) {
            if (text_.substr(pos_, 2) != "\\u") return fail(escape, "a low surrogate after a high one", "a lone high surrogate");
            pos_ += 2;
            const auto lo = hex4();
            if (!lo || *lo < 0xDC00 || *lo > 0xDFFF) {
              return fail(escape, "a low surrogate after a high one", "a lone high surrogate");
            }
            cp = 0x10000 + ((cp - 0xD800) << 10) + (*lo - 0xDC00);
          }
          append_utf8(out, cp);
          continue;  // hex4() moved past the digits
        }
        default: return fail(escape, "an escape: \\\" \\\\ \\/ \\b \\f \\n \\r \\t or \\uXXXX", "an unknown escape");
      }
      ++pos_;
    }
  }

  bool number(Value& out) {
    const Position start = here();
    const size_t begin = pos_;
    if (peek() == '-') ++pos_;
    if (peek() == '0') {
      ++pos_;
    } else if (is_digit(peek())) {
      while (is_digit(peek())) ++pos_;
    } else {
      return fail(here(), "a digit", "a number needs digits");
    }
    if (peek() == '.') {
      ++pos_;
      if (!is_digit(peek())) return fail(here(), "a digit after '.'", "a number needs digits after '.'");
      while (is_digit(peek())) ++pos_;
    }
    if (peek() == 'e' || peek() == 'E') {
      ++pos_;
      if (peek() == '+' || peek() == '-') ++pos_;
      if (!is_digit(peek())) return fail(here(), "a digit in the exponent", "a number needs digits in its exponent");
      while (is_digit(peek())) ++pos_;
    }
    out.kind = Value::Kind::kNumber;
    const char* first = text_.data() + begin;
    const char* last = text_.data() + pos_;
    const auto [ptr, ec] = std::from_chars(first, last, out.number);
    if (ec != std::errc() || ptr != last) {
      pos_ = begin;
      return fail(start, "a number a double can hold", "number out of range");
    }
    return true;
  }

  std::string_view text_;
  size_t pos_ = 0;
  size_t line_ = 1;
  size_t line_start_ = 0;
  std::vector<Segment> segments_;
  std::vector<Problem> duplicates_;
  std::optional<Problem> error_;
};

}  // namespace

const Member* Value::find(std::string_view key) const {
  for (const Member& m : members) {
    if (m.key == key) return &m;
  }
  return nullptr;
}

Result<Document, Problem> read(std::string_view text) { return Reader(text).run(); }

std::string path_with_key(const std::string& path, std::string_view key) {
  if (is_plain_name(key)) return path + "." + std::string(key);
  std::string out = path + "[\"";
  for (char c : key) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (u < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", u);
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"]";
}

std::string path_with_index(const std::string& path, size_t index) { return path + "[" + std::to_string(index) + "]"; }

std::string excerpt(std::string_view text, size_t begin, size_t end, size_t max) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  end = std::min(end, text.size());
  size_t i = begin;
  while (i < end) {
    if (out.size() >= max) {
      out += "...";
      break;
    }
    const char c = text[i];
    const auto u = static_cast<unsigned char>(c);
    if (is_blank(c)) {
      if (out.empty() || out.back() != ' ') out += ' ';
      ++i;
    } else if (u < 0x20 || u == 0x7F) {
      out += "\\x";
      out += kHex[u >> 4];
      out += kHex[u & 0xF];
      ++i;
    } else if (u >= 0x80) {
      const size_t n = utf8_length(text, i);
      if (n == 0 || i + n > end) {
        out += "\\x";
        out += kHex[u >> 4];
        out += kHex[u & 0xF];
        ++i;
      } else {
        out.append(text.substr(i, n));
        i += n;
      }
    } else {
      out += c;
      ++i;
    }
  }
  return out;
}

}  // namespace hmc::json
