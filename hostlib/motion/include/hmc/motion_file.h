// Motion files: a choreography written once (home, moves, coordinated moves, servos, lights,
// waits, repeats), as JSON, and its validation (docs/motion-files.md, docs/motion-file.schema.json).
//
// load_motion_file() reads and checks a whole file before anything can move: every mistake is
// reported, not just the first, each with the file, line and column, the JSON path, what was
// expected and what was found. Distances and speeds are converted here, once, into the units
// the board counts: steps at the motor's microstep, steps/s, steps/s², steps/s³. Ranges are
// checked against the board's rules, soft travel limits included (those a file declares).
//
// A file may name the machine profile it was written for (profile.h, docs/config.md): its
// motors are then the profile's axes, by name, in the axes' units (mm, mm/s, mm/s² on a linear
// axis; deg on a rotary one), direction and soft limits. When a file has mistakes, the ones that
// planning finds (a `to` before the position is known, a `by` beyond a soft limit) are reported
// with them, as far as the broken steps allow: the whole file is checked in one pass.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "hmc/profile.h"
#include "hmc/result.h"

namespace hmc::motion {

inline constexpr int kFormatVersion = 1;

// Where something is in the file.
struct Location {
  std::string file;
  uint32_t line = 0;    // 1-based; 0 when unknown (the file as a whole)
  uint32_t column = 0;  // 1-based, in bytes
  std::string path;     // JSON path: "$.steps[3].move.speed"
};

struct FileError {
  Location where;
  std::string expected;  // "a number of steps/s above 0", "one of home, move, ..."
  std::string found;     // the value as written, or "nothing"
  std::string message;   // the sentence shown to people
  // "FILE:LINE:COLUMN: PATH: MESSAGE (expected X, found Y)", one line per error; the parenthesis
  // leaves out what the message already says, and a file that cannot be read is "FILE: MESSAGE".
  std::string text() const;
};

// The top-level "motors": a name for a stepper and how its steps map to the world.
struct MotorConfig {
  std::string name;                 // its key in "motors": "pan"
  uint32_t motor = 1;               // the board's stepper, 1-3
  uint32_t full_steps_per_rev = 200;
  uint32_t microstep = 16;          // 1, 2, 4 ... 256: the microstep every move of this motor uses
  double gear_ratio = 1.0;          // motor turns per output turn (degrees and revolutions are of the output)
  double speed = 1000.0;            // default speed, steps/s
  double accel = 0.0;               // default acceleration, steps/s² (0: constant rate)
  std::optional<double> min_position;  // soft travel limits, in steps from home
  std::optional<double> max_position;
  // The profile axis it is (a file in a rig's terms): its homing and soft limits are the
  // profile's, as `hmc home` applies them.
  std::optional<hmc::Axis> axis;
  Location where;

  double steps_per_degree() const { return full_steps_per_rev * microstep * gear_ratio / 360.0; }
};

enum class ProfileKind : uint8_t {
  kConstant,   // the seed's: one rate from start to end
  kStaged,     // the seed's staged ramp: low -> mid -> high -> mid -> low, N rates
  kTrapezoid,  // constant acceleration up and down
  kSCurve,     // jerk-limited acceleration
};

struct Profile {
  ProfileKind kind = ProfileKind::kConstant;
  double speed = 0;      // top speed, steps/s
  double accel = 0;      // steps/s² (trapezoid, S-curve; staged: the ramp the stages follow)
  double jerk = 0;       // steps/s³ (S-curve)
  uint32_t stages = 3;   // staged: rates from low to the top speed, the top included (seed: 3)
};

// One motor's move; distances in steps at the motor's microstep.
struct Move {
  std::string motor;      // a name from "motors"
  double distance = 0;    // relative steps (signed), or the target with `absolute`
  bool absolute = false;  // distance is a position from home
  // The distance or position in steps before rounding, when it is not a whole step (a millimetre
  // or degree between steps). Planning counts the end of a relative move from the exact end of
  // the one before, so that roundings never add up beyond half a step.
  std::optional<double> exact;
  Profile profile;
  Location where;
};

struct Colour {
  uint32_t r = 0, g = 0, b = 0, w = 0;
};

struct HomeStep {
  std::vector<std::string> motors;  // homed one after another
};
struct MoveStep {
  Move move;
  bool wait = true;  // false: go on at once (the motor keeps moving)
};
// Several motors that start together and arrive together.
struct TogetherStep {
  std::vector<Move> moves;
};
struct ServoStep {
  uint32_t servo = 1;
  double angle = 90;  // degrees, within the board's SVM range (10-170)
};
struct LedStep {
  uint32_t strip = 1;
  Colour colour;
  std::optional<Colour> from;  // a fade starts here (default: the strip's current colour)
  double fade_ms = 0;          // 0: at once
};
struct WaitStep {
  double ms = 0;                      // a pause, or
  std::vector<std::string> until_done;  // until these motors rest
};
struct StopStep {
  std::vector<std::string> motors;  // empty: all
};
struct Step;
struct RepeatStep {
  uint32_t count = 1;
  std::vector<Step> steps;
};

struct Step {
  std::variant<HomeStep, MoveStep, TogetherStep, ServoStep, LedStep, WaitStep, StopStep, RepeatStep> action;
  std::string label;  // optional "label": shown while it runs
  Location where;
};

struct MotionFile {
  int version = kFormatVersion;
  std::string path;
  std::string name;  // optional "name"
  std::string profile;  // the machine profile's file: the one the file names, or the program's it uses
  std::vector<MotorConfig> motors;
  std::vector<Step> steps;
  // What is worth saying though it is no mistake: each value rounded to a whole step, where it is.
  std::vector<FileError> notes;

  const MotorConfig* motor(const std::string& name) const;
};

struct ReadOptions {
  // The program's chosen profile (hmc's --profile, HMC_PROFILE or default config; Python's
  // Board(profile=)): the motors of a file that names none and declares no "motors".
  const hmc::Profile* profile = nullptr;
  // How `profile` was chosen, as messages name it ("--profile", "HMC_PROFILE"); empty: by default.
  // A file naming another profile than one chosen so is a mistake, at its "profile" (it was
  // written for another rig); a default gives way to the file's own profile, with a note.
  // "Another" is another file whose text differs too: a copy of the same profile is the same.
  std::string profile_chosen_by;
  // Loads the profile a file names (its "profile", and the motion file's path); empty: the
  // named file, relative to the motion file's folder, with load_profile(). An error is a sentence.
  std::function<Result<hmc::Profile, std::string>(const std::string& name, const std::string& motion_file)>
      load_profile;
};

// Parses and validates `text` (from `path`, used in messages and to find a named profile). All
// errors, in file order.
Result<MotionFile, std::vector<FileError>> parse_motion_file(const std::string& text, const std::string& path,
                                                             const ReadOptions& options = {});
// Reads the file, then parse_motion_file(); an unreadable file is one error.
Result<MotionFile, std::vector<FileError>> load_motion_file(const std::string& path, const ReadOptions& options = {});

}  // namespace hmc::motion
