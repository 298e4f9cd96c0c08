// Motion files (motion_file.h, docs/motion-files.md): reads the JSON with positions
// (json_reader.h), checks every key and value against the format and the board's rules,
// converts distances and rates to steps, and collects every mistake with where it is.
//
// Checking goes on after a mistake: a broken value yields no step, and what depends on it
// (unit conversions of a motor whose gearing is broken, names when "motors" is missing) is not
// checked, so one mistake is reported once.
#include "hmc/motion_file.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <system_error>
#include <utility>

#include "motion_file_check.h"

namespace hmc::motion {

namespace {

using reading::fmt;
using reading::Kind;
using reading::kMaxUnrolledSteps;
using reading::Value;

constexpr std::string_view kTopKeys[] = {"hmc_motion", "name", "motors", "steps"};

// One file: the document, its top level, and the parts that read the rest.
class Checker {
 public:
  Checker(std::string_view text, const std::string& file) : text_(text), file_(file), r_(text, file) {}

  Result<MotionFile, std::vector<FileError>> run() {
    std::vector<FileError>& errors_ = r_.errors();
    auto doc = json::read(text_);
    if (!doc) {
      const json::Problem& p = doc.error();
      r_.add(p.at, p.path, p.expected, p.found, p.message);
      return std::move(errors_);
    }
    for (const json::Problem& p : doc->duplicates) r_.add(p.at, p.path, p.expected, p.found, p.message);
    file_data_.path = file_;
    top(doc->root);
    if (!errors_.empty()) {
      std::stable_sort(errors_.begin(), errors_.end(), [](const FileError& a, const FileError& b) {
        return a.where.line != b.where.line ? a.where.line < b.where.line : a.where.column < b.where.column;
      });
      return std::move(errors_);
    }
    return std::move(file_data_);
  }

 private:
  void top(const Value& root) {
    const std::string path = "$";
    if (!root.is(Kind::kObject)) {
      r_.bad(root, path, "an object with hmc_motion, motors and steps", "a motion file is a JSON object");
      return;
    }
    r_.known_keys(root, path, kTopKeys);

    if (const Value* v = r_.get(root, "hmc_motion")) {
      const std::string p = json::path_with_key(path, "hmc_motion");
      if (!v->is(Kind::kNumber)) {
        r_.wrong_type(*v, p, "the format version 1");
      } else if (v->number != kFormatVersion) {
        r_.bad(*v, p, "1", "format version " + fmt(v->number) + " is not one this reader knows");
      }
    } else {
      r_.missing(root, path, "hmc_motion", "the format version 1");
    }

    if (const Value* v = r_.get(root, "name")) {
      if (auto s = r_.string(*v, json::path_with_key(path, "name"))) file_data_.name = *s;
    }

    if (const Value* v = r_.get(root, "motors")) {
      motors_.read(*v, json::path_with_key(path, "motors"), file_data_.motors);
    } else {
      r_.missing(root, path, "motors", "an object of 1 to 3 motors");
    }

    if (const Value* v = r_.get(root, "steps")) {
      const std::string p = json::path_with_key(path, "steps");
      if (!v->is(Kind::kArray)) {
        r_.wrong_type(*v, p, "a list of steps");
      } else if (v->items.empty()) {
        r_.bad(*v, p, "a list of at least one step", "a motion file needs at least one step");
      } else {
        const uint64_t total = steps_.steps(*v, p, 0, file_data_.steps);
        if (total > kMaxUnrolledSteps) {
          r_.bad(*v, p, "at most " + fmt(kMaxUnrolledSteps) + " steps once repeats are unrolled",
                 "the file unrolls to " + fmt(static_cast<double>(total)) + " steps");
        }
      }
    } else {
      r_.missing(root, path, "steps", "a list of steps");
    }
  }

  std::string_view text_;
  const std::string& file_;
  reading::Reporter r_;
  reading::QuantityReader q_{r_};
  reading::MotorTable motors_{r_, q_};
  reading::StepChecker steps_{r_, q_, motors_};
  MotionFile file_data_;
};

}  // namespace

std::string FileError::text() const {
  std::string out = where.file;
  if (where.line > 0) out += ":" + std::to_string(where.line) + ":" + std::to_string(where.column);
  out += ": ";
  if (!where.path.empty()) out += where.path + ": ";
  out += message;
  // What the message already says is not repeated.
  std::string detail;
  if (!expected.empty() && message.find("expected " + expected) == std::string::npos) detail = "expected " + expected;
  if (!found.empty()) detail += (detail.empty() ? "" : ", ") + std::string("found ") + found;
  if (!detail.empty()) out += " (" + detail + ")";
  return out;
}

const MotorConfig* MotionFile::motor(const std::string& motor_name) const {
  for (const MotorConfig& m : motors) {
    if (m.name == motor_name) return &m;
  }
  return nullptr;
}

Result<MotionFile, std::vector<FileError>> parse_motion_file(const std::string& text, const std::string& path) {
  return Checker(text, path).run();
}

Result<MotionFile, std::vector<FileError>> load_motion_file(const std::string& path) {
  const auto unreadable = [&](int error) {
    FileError e;
    e.where.file = path;
    e.message = "cannot read the file: " + std::error_code(error, std::generic_category()).message();
    return std::vector<FileError>{e};
  };
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return unreadable(errno);
  std::string text;
  char buf[65536];
  size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, n);
  const bool failed = std::ferror(f) != 0;
  const int error = errno;
  std::fclose(f);
  if (failed) return unreadable(error);
  return parse_motion_file(text, path);
}

}  // namespace hmc::motion