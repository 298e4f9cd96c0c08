// What the Python module hands back: plain records (status, events, frames, plans), filled from
// libhmc's types while the GIL is held, and the exceptions it raises.
#pragma once

#include <pybind11/pybind11.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hmc/board_frame.h"
#include "hmc/codec.h"
#include "hmc/motion_file.h"
#include "hmc/profile.h"
#include "hmc/session.h"

namespace hmc::python {

namespace py = pybind11;

// A number with a unit, as `hmc.mm(250)`, `hmc.deg(-90)` or "20mm/s" give it.
struct PyQuantity {
  Quantity quantity;
  std::string text() const;  // "250mm", "20mm/s": what parse_quantity reads back
};

struct MotorRecord {
  uint32_t motor = 1;
  std::string state;          // idle, moving, homing, changing, self_test
  int64_t position = 0;       // steps at the motor's microstep, as `hmc move` counts them
  int64_t target = 0;         // steps at the motor's microstep
  int64_t board_position = 0; // 1/256 full step, exactly as the board reports it
  uint32_t microstep = 1;
  uint32_t rate = 0;          // steps/s
  bool homed = false;
  bool endless = false;
  bool switch_reverse = false;
  bool switch_forward = false;
  std::optional<std::string> last_end;  // completed, stopped, limit, emergency, dropped, watchdog
  std::optional<std::string> axis;      // the profile's axis on this motor
  std::optional<std::string> unit;      // mm or deg
  std::optional<double> units;          // position in the axis's unit
  std::optional<double> target_units;
  std::optional<double> rate_units;     // unit/s
};

struct ServoRecord {
  uint32_t servo = 1;
  uint32_t pulse_us = 0;  // 0: released
};

struct StripRecord {
  uint32_t strip = 1;
  uint32_t r = 0, g = 0, b = 0, w = 0;
  std::string colour;  // "#rrggbbww"
};

struct StatusRecord {
  std::string board;      // the board's description
  std::string firmware;   // "v2" or "seed"
  bool reported = false;  // from the board (v2); seed: what this session sent
  bool emergency = false;
  std::vector<MotorRecord> motors;
  std::vector<ServoRecord> servos;
  std::vector<StripRecord> strips;
  std::optional<uint32_t> watchdog_ms;  // the link watchdog's timeout, 0 off; None: no watchdog
  bool watchdog_fired = false;
  std::optional<std::string> last_reset;
};

struct EventRecord {
  std::string kind;  // move_done, watchdog, homed, limit, emergency, driver_fault, booted, reset
  std::optional<uint32_t> motor;
  std::optional<std::string> how;       // move_done: completed, stopped, limit, emergency, dropped
  std::optional<int64_t> position;      // steps at the motor's microstep
  std::optional<int64_t> board_position;  // 1/256 full step
  std::optional<bool> pressed;          // limit, emergency
  std::optional<uint32_t> end;          // limit: 0 reverse, 1 forward
  std::optional<bool> homed;            // homed
  std::string text;                     // in words
  std::string line;                     // the frame as it came
  double time = 0;                      // time.monotonic() when it was read
};

struct FrameRecord {
  std::string name;         // STM, SVM, ... or ACK, NAK, EVD, ...
  bool event = false;       // a board frame sent unprompted
  py::dict values;          // field -> value, in wire order
  std::string description;  // in words
  std::string frame;        // the canonical frame
  bool canonical = true;    // the input was written canonically
  std::vector<std::string> warnings;
};

struct ProgressRecord {
  std::string kind;  // started, done, returning
  size_t step = 0;   // 1-based action index (0 for returning)
  size_t total = 0;
  std::string description;
  double elapsed_s = 0;
  double remaining_s = 0;
};

// One mistake in a motion file.
struct MistakeRecord {
  std::string file;
  uint32_t line = 0;
  uint32_t column = 0;
  std::string path;  // JSON path: "$.steps[3].move.speed"
  std::string expected;
  std::string found;
  std::string message;
};

MotorRecord motor_record(const MotorStatus& motor, const std::optional<MotionEnd>& last_end, const Axis* axis);
StatusRecord status_record(const Session& session, const Profile* profile);
// The event `frame` is, in words and values; `microstep` converts its position to steps.
EventRecord event_record(const BoardFrame& frame, std::string_view line, uint32_t microstep, double time);
FrameRecord command_record(const Decoded& decoded, proto::ChecksumMode mode);
FrameRecord board_frame_record(const BoardFrame& frame, proto::ChecksumMode mode);

// The exception types, made once when the module loads.
struct Exceptions {
  py::handle error, refused, invalid_command, too_old, no_reply, link_lost, port_error, ended_early, frame_error,
      motion_file_error, profile_error, rounding_warning;
};
const Exceptions& exceptions();
void make_exceptions(py::module_& m);

// Raises `type(message)` with `attributes` set on the exception object.
[[noreturn]] void raise(py::handle type, const std::string& message, const py::dict& attributes = py::dict());
// A session's error as its exception (KeyboardInterrupt for an interruption).
[[noreturn]] void raise_session_error(const SessionError& error);
// A codec refusal as hmc.FrameError with its diagnostic.
[[noreturn]] void raise_diagnostic(const Diagnostic& diagnostic, const std::string& input);
// Values rounded to a whole step, each said as an hmc.RoundingWarning.
void warn_rounding(const std::vector<std::string>& notes);
void warn_rounding(const std::vector<motion::FileError>& notes);
// A profile's mistakes as hmc.ProfileError (an unreadable file: hmc.PortError).
[[noreturn]] void raise_profile_error(const ProfileError& error);
// Every mistake of a motion file as hmc.MotionFileError (errors: a list of Mistake).
[[noreturn]] void raise_motion_file_error(const std::vector<motion::FileError>& errors);
py::dict diagnostic_attributes(const Diagnostic& diagnostic);

}  // namespace hmc::python
