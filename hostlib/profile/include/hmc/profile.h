// The machine profile: a TOML file that describes one rig once — the port, baud and firmware
// kind, and each axis by name: which motor drives it, its steps per turn, microstep and gearing,
// whether it is linear (mm per turn, a belt's pulley teeth and pitch, or a screw's lead) or
// rotary (degrees), which way is positive, its soft limits, default speed and acceleration, and
// how it homes (docs/config.md). With it, positions, speeds and accelerations in the axis's own
// units become exact step counts, and the board's step counts become millimetres and degrees.
//
// Loading reports every semantic mistake at once, each with its line and column; a TOML syntax
// error stops the reader, so it is reported alone. This module uses only the protocol module
// (the board's facts: motors, microsteps, which motors have switches); the TOML reader stays
// inside profile.cpp.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hmc/board_frame.h"
#include "hmc/result.h"
#include "hmc/units.h"

namespace hmc {

// Where a value stands in the profile file (1-based; 0 when not from a file).
struct ProfilePlace {
  uint32_t line = 0;
  uint32_t column = 0;
};

struct AxisHoming {
  uint32_t end = 0;                    // the switch end it seeks: 0 reverse, 1 forward (motor's sense)
  std::optional<double> seek_speed;    // axis units/s while seeking (board default otherwise)
  std::optional<double> pull_off;      // axis units backed off the switch after it closes
  std::optional<double> locate_speed;  // axis units/s re-approaching slowly after the pull-off
};

// A value converted to steps: the nearest whole step, and how far that is from the exact value.
struct StepCount {
  int64_t steps = 0;   // at the axis's microstep
  double exact = 0;    // the value in steps before rounding
  bool rounded() const;  // more than a millionth of a step away
};

struct Axis {
  std::string name;
  uint32_t motor = 1;
  uint32_t steps_per_rev = 200;  // full steps per motor turn
  uint32_t microstep = 16;       // 1, 2, 4 ... 256
  double gear_ratio = 1;         // motor turns per output turn
  bool rotary = false;           // degrees; else millimetres
  double mm_per_rev = 0;         // linear: output travel per output turn
  bool invert = false;           // positive axis direction = the motor's reverse
  std::optional<double> limit_min, limit_max;  // soft limits, axis units
  std::optional<double> speed;   // default speed, axis units/s
  std::optional<double> accel;   // default acceleration, axis units/s^2 (0: constant rate)
  std::optional<AxisHoming> homing;
  ProfilePlace place;            // its table in the file

  // The axis's own unit: mm or deg.
  Unit unit() const { return rotary ? Unit::kDeg : Unit::kMm; }
  // The units a quantity for this axis may be given in, for messages: "mm, rev or steps".
  std::string units_words() const;
  // Motor steps at the axis's microstep per axis unit (mm or deg).
  double steps_per_unit() const;
  // Steps at the microstep per output turn.
  double steps_per_rev_out() const;

  // A quantity in steps (its sign as given: a distance, speed or acceleration in the axis's
  // sense), or why it does not fit this axis: the wrong unit (mm on a rotary axis) or the wrong
  // dimension (a speed where a position is wanted).
  Result<StepCount> to_steps(const Quantity& quantity, Dimension wanted) const;
  // An axis position (axis units) as the board's position in 1/256 full step, direction applied.
  // Absolute positions are converted, never each relative move, so rounding never accumulates.
  StepCount to_board_position(double axis_position) const;
  // The board's position (1/256 full step) in axis units, direction applied.
  double from_board_position(int64_t position) const;
  // A rate in steps/s at `microstep` in axis units/s.
  double from_board_rate(uint32_t rate, uint32_t microstep) const;
};

struct Profile {
  std::string path;
  std::optional<std::string> port;
  std::optional<uint32_t> baud;
  std::optional<std::string> firmware;  // auto | v2 | seed
  std::vector<Axis> axes;               // by motor number

  // The axis with this name, or the one driven by motor "1"-"3"; nullptr when none.
  const Axis* find(std::string_view name_or_motor) const;
  const Axis* axis_of_motor(uint32_t motor) const;
};

struct ProfileMistake {
  ProfilePlace place;
  std::string message;
};

struct ProfileError {
  std::string path;
  bool unreadable = false;  // the file could not be read (message in mistakes[0])
  bool syntax = false;      // a TOML syntax error, reported alone
  std::vector<ProfileMistake> mistakes;
  // "config.toml:12:9: unknown key 'spead' in axis 'slide'", one per line.
  std::string text() const;
};

// Reads and checks a profile; every mistake is in the error.
Result<Profile, ProfileError> parse_profile(std::string_view text, const std::string& path);
Result<Profile, ProfileError> load_profile(const std::string& path);

// The default profile's path: $XDG_CONFIG_HOME/hmc/config.toml, else ~/.config/hmc/config.toml.
Result<std::string> default_profile_path();

// Which profile a program uses: the one it was given (`--profile`, may be empty), else
// HMC_PROFILE, else the default path. One rule for every program (the CLI, hmc-desk).
struct ProfileSource {
  std::string path;
  std::string from;  // "--profile", "HMC_PROFILE" or "default"
  bool exists = false;
};
Result<ProfileSource> find_profile(const std::string& given);

}  // namespace hmc
