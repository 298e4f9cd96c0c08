// Motion files (motion_file.h, docs/motion-files.md): reads the JSON with positions
// (json_reader.h), checks every key and value against the format and the board's rules,
// converts distances and rates to steps, and collects every mistake with where it is.
//
// Checking goes on after a mistake: a broken value yields no step, and what depends on it
// (unit conversions of a motor whose gearing is broken, names when "motors" is missing) is not
// checked, so one mistake is reported once. A file with mistakes is also planned as far as its
// sound steps allow (plan_check.h), so that planning's mistakes come in the same run.
#include "hmc/motion_file.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <system_error>
#include <utility>

#include "motion_file_check.h"
#include "plan_check.h"

namespace hmc::motion {

namespace {

using reading::fmt;
using reading::Kind;
using reading::kMaxUnrolledSteps;
using reading::Value;

constexpr std::string_view kTopKeys[] = {"hmc_motion", "name", "profile", "motors", "steps"};

// One file: the document, its top level, and the parts that read the rest.
class Checker {
 public:
  Checker(std::string_view text, const std::string& file, const ReadOptions& options)
      : text_(text), file_(file), options_(options), r_(text, file) {}

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
      // One pass: what planning finds in the steps that are sound, beside what reading found.
      for (FileError& e : planning::position_mistakes(file_data_, steps_.broken())) errors_.push_back(std::move(e));
      std::stable_sort(errors_.begin(), errors_.end(), [](const FileError& a, const FileError& b) {
        return a.where.line != b.where.line ? a.where.line < b.where.line : a.where.column < b.where.column;
      });
      return std::move(errors_);
    }
    file_data_.notes = std::move(r_.notes());
    std::stable_sort(file_data_.notes.begin(), file_data_.notes.end(), [](const FileError& a, const FileError& b) {
      return a.where.line != b.where.line ? a.where.line < b.where.line : a.where.column < b.where.column;
    });
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

    // The motors: the file's own, or the axes of the profile it names (or that it is read with).
    const Value* named = r_.get(root, "profile");
    std::optional<hmc::Profile> profile;
    if (named != nullptr) {
      const std::string p = json::path_with_key(path, "profile");
      if (auto name = r_.string(*named, p)) {
        auto loaded = options_.load_profile ? options_.load_profile(*name, file_) : load_named_profile(*name, file_);
        if (loaded) {
          profile = std::move(*loaded);
          file_data_.profile = profile->path;
          if (options_.profile != nullptr && !same_profile(profile->path, options_.profile->path)) {
            differs_from_chosen(*named, p);
          }
        } else {
          r_.bad(*named, p, "a machine profile without mistakes (docs/config.md)", loaded.error());
        }
      }
    }
    if (const Value* v = r_.get(root, "motors")) {
      if (named != nullptr) {
        r_.bad(*v, json::path_with_key(path, "motors"), "either \"profile\" or \"motors\"",
               "a file that names a profile takes its motors from the profile's axes: it declares no \"motors\"");
      } else {
        motors_.read(*v, json::path_with_key(path, "motors"), file_data_.motors);
      }
    } else if (profile) {
      motors_.from_profile(*profile, r_.location(named->at, json::path_with_key(path, "profile")), file_data_.motors);
    } else if (named == nullptr && options_.profile != nullptr) {
      motors_.from_profile(*options_.profile, r_.location(root.at, path), file_data_.motors);
      file_data_.profile = options_.profile->path;
    } else if (named == nullptr) {
      r_.missing(root, path, "motors", "an object of 1 to 3 motors, or a \"profile\"");
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

  // The file names a profile other than the program's: a mistake when the program's was chosen
  // (the file was written for another rig), else a note that the file's is used.
  void differs_from_chosen(const Value& named, const std::string& path) {
    const std::string& mine = file_data_.profile;
    const std::string& chosen = options_.profile->path;
    if (options_.profile_chosen_by.empty()) {
      r_.note(named, path, "the file's profile " + mine + " is used, not the default " + chosen);
      return;
    }
    const std::string& by = options_.profile_chosen_by;
    r_.add(named.at, path, "", "",
           "the file was written for the profile " + mine + ", not for " + chosen + ", which " + by +
               " chooses: give " + by + " the file's profile, or none");
  }

  // Two profile files are the same when they are one file, or their texts are equal (a copy).
  static bool same_profile(const std::string& a, const std::string& b) {
    std::error_code error;
    if (std::filesystem::equivalent(a, b, error)) return true;
    const auto text = [](const std::string& path) -> std::optional<std::string> {
      std::ifstream in(path, std::ios::binary);
      if (!in) return std::nullopt;
      return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    };
    const std::optional<std::string> x = text(a);
    return x && x == text(b);
  }

  // The profile a file names, relative to the motion file's folder.
  static Result<hmc::Profile, std::string> load_named_profile(const std::string& name, const std::string& motion_file) {
    std::filesystem::path p(name);
    if (p.is_relative()) p = std::filesystem::path(motion_file).parent_path() / p;
    auto loaded = load_profile(p.string());
    if (loaded) return std::move(*loaded);
    const ProfileError& e = loaded.error();
    if (e.unreadable || e.mistakes.empty()) {
      return "cannot read the profile " + p.string() + (e.mistakes.empty() ? "" : ": " + e.mistakes[0].message);
    }
    const ProfileMistake& first = e.mistakes[0];
    return "the profile " + p.string() + " has " + std::to_string(e.mistakes.size()) +
           (e.mistakes.size() == 1 ? " mistake" : " mistakes") + " (`hmc config check` lists them); the first, at " +
           std::to_string(first.place.line) + ":" + std::to_string(first.place.column) + ": " + first.message;
  }

  std::string_view text_;
  const std::string& file_;
  const ReadOptions& options_;
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

Result<MotionFile, std::vector<FileError>> parse_motion_file(const std::string& text, const std::string& path,
                                                             const ReadOptions& options) {
  return Checker(text, path, options).run();
}

Result<MotionFile, std::vector<FileError>> load_motion_file(const std::string& path, const ReadOptions& options) {
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
  return parse_motion_file(text, path, options);
}

}  // namespace hmc::motion