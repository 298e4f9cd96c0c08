// Records filled from libhmc's types, and the module's exceptions.
#include "records.h"

#include <cmath>
#include <cstdio>
#include <initializer_list>

#include <pybind11/stl.h>

#include "hmc/axis_moves.h"

namespace hmc::python {
namespace {

Exceptions g_exceptions;

int64_t steps_at(int64_t position, uint32_t microstep) {
  return static_cast<int64_t>(std::llround(static_cast<double>(position) * microstep / 256.0));
}

std::string colour_text(uint32_t r, uint32_t g, uint32_t b, uint32_t w) {
  char text[16];
  std::snprintf(text, sizeof text, "#%02x%02x%02x%02x", r & 0xFFu, g & 0xFFu, b & 0xFFu, w & 0xFFu);
  return text;
}

py::dict values_dict(const proto::FieldSpec* fields, const CommandValues& values) {
  py::dict out;
  for (uint32_t i = 0; i < values.count; ++i) out[fields[i].name] = values.values[i];
  return out;
}

py::handle new_exception(py::module_& m, const char* name, py::handle base, const char* doc) {
  const std::string qualified = std::string("hmc.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, base.ptr(), nullptr);
  if (type == nullptr) throw py::error_already_set();
  m.add_object(name, py::handle(type));  // the module keeps the reference
  return type;
}

py::handle new_exception(py::module_& m, const char* name, std::initializer_list<py::handle> bases, const char* doc) {
  py::tuple tuple(bases.size());
  size_t i = 0;
  for (py::handle b : bases) tuple[i++] = py::reinterpret_borrow<py::object>(b);
  return new_exception(m, name, tuple, doc);
}

py::object reason_name(proto::Reason reason) {
  if (reason == proto::Reason::kOk) return py::none();
  if (static_cast<uint32_t>(reason) >= proto::kReasonCount) return py::str("reason_" + std::to_string(static_cast<int>(reason)));
  return py::str(proto::reason_spec(reason).name);
}

}  // namespace

std::string PyQuantity::text() const {
  char number[40];
  std::snprintf(number, sizeof number, "%.17g", quantity.value);
  return number + unit_text(quantity.unit, quantity.dimension);
}

MotorRecord motor_record(const MotorStatus& m, const std::optional<MotionEnd>& last_end, const Axis* axis) {
  MotorRecord r;
  r.motor = m.motor;
  r.state = motor_state_name(m.state);
  r.position = steps_at(m.position, m.microstep);
  r.target = steps_at(m.target, m.microstep);
  r.board_position = m.position;
  r.microstep = m.microstep;
  r.rate = m.rate;
  r.homed = m.homed;
  r.endless = m.endless;
  r.switch_reverse = (m.switches & 1u) != 0;
  r.switch_forward = (m.switches & 2u) != 0;
  if (last_end) r.last_end = motion_end_name(*last_end);
  if (axis != nullptr) {
    r.axis = axis->name;
    r.unit = unit_name(axis->unit());
    r.units = axis->from_board_position(m.position);
    r.target_units = axis->from_board_position(m.target);
    r.rate_units = axis->from_board_rate(m.rate, m.microstep);
  }
  return r;
}

StatusRecord status_record(const Session& s, const Profile* profile) {
  const BoardModel& model = s.model();
  StatusRecord r;
  r.board = s.description();
  r.firmware = s.firmware() == Firmware::kV2 ? "v2" : "seed";
  r.reported = model.reported;
  r.emergency = model.board.emergency;
  for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
    r.motors.push_back(motor_record(model.motor(m), model.last_end[m - 1], profile ? profile->axis_of_motor(m) : nullptr));
  }
  r.servos = {ServoRecord{1, model.board.servo1_us}, ServoRecord{2, model.board.servo2_us}};
  for (const StripStatus& l : model.strips) r.strips.push_back(StripRecord{l.strip, l.r, l.g, l.b, l.w, colour_text(l.r, l.g, l.b, l.w)});
  if (model.watchdog) {
    r.watchdog_ms = model.watchdog->timeout_ms;
    r.watchdog_fired = model.watchdog->fired;
  }
  if (model.last_reset) r.last_reset = reset_text(*model.last_reset);
  return r;
}

EventRecord event_record(const BoardFrame& frame, std::string_view line, uint32_t microstep, double time) {
  EventRecord e;
  e.text = describe(frame);
  e.line = std::string(line);
  e.time = time;
  const auto at = [&](uint32_t motor, int64_t position) {
    e.motor = motor;
    e.board_position = position;
    e.position = steps_at(position, microstep);
  };
  if (const auto* d = std::get_if<MotionEnded>(&frame)) {
    e.kind = d->how == MotionEnd::kWatchdog ? "watchdog" : "move_done";
    e.how = motion_end_name(d->how);
    at(d->motor, d->position);
  } else if (const auto* h = std::get_if<HomingEnded>(&frame)) {
    e.kind = "homed";
    e.homed = h->homed;
    at(h->motor, h->position);
  } else if (const auto* l = std::get_if<LimitChanged>(&frame)) {
    e.kind = "limit";
    e.motor = l->motor;
    e.end = l->end;
    e.pressed = l->pressed;
  } else if (const auto* em = std::get_if<EmergencyChanged>(&frame)) {
    e.kind = "emergency";
    e.pressed = em->pressed;
  } else if (const auto* f = std::get_if<DriverFault>(&frame)) {
    e.kind = "driver_fault";
    e.motor = f->motor;
  } else if (std::holds_alternative<Booted>(frame)) {
    e.kind = "booted";
  } else {
    e.kind = "reset";
  }
  return e;
}

FrameRecord command_record(const Decoded& decoded, proto::ChecksumMode mode) {
  FrameRecord r;
  const proto::CommandSpec& spec = command_spec(decoded.command);
  r.name = spec.name;
  r.values = values_dict(spec.fields, command_values(decoded.command));
  r.description = describe(decoded.command);
  r.frame = encode(decoded.command, mode).value();
  r.canonical = decoded.canonical;
  for (const Warning& w : decoded.warnings) r.warnings.push_back(w.message);
  return r;
}

FrameRecord board_frame_record(const BoardFrame& frame, proto::ChecksumMode mode) {
  FrameRecord r;
  const proto::BoardFrameSpec& spec = board_frame_spec(frame);
  r.name = spec.name;
  r.event = is_event(frame);
  if (Result<CommandValues, Diagnostic> values = board_frame_values(frame)) r.values = values_dict(spec.fields, *values);
  r.description = describe(frame);
  if (Result<std::string, Diagnostic> text = encode_board_frame(frame, mode)) r.frame = *text;
  return r;
}

const Exceptions& exceptions() { return g_exceptions; }

void make_exceptions(py::module_& m) {
  Exceptions& x = g_exceptions;
  x.error = new_exception(m, "Error", PyExc_Exception, "Every error of the hmc module: the message says what to do.");
  x.refused = new_exception(m, "Refused", x.error,
                            "A command was refused: by the host's checks against the board's rules (by_board False) or by "
                            "the board's NAK (by_board True: token and offset say where in the line). reason is the "
                            "protocol's reason name (e.g. 'limit_pressed') or None, code its number.");
  x.invalid_command = new_exception(m, "InvalidCommand", {x.refused, PyExc_ValueError},
                                    "A command outside the protocol's ranges, or arguments that do not make one (a unit "
                                    "the axis does not have, two targets).");
  x.too_old = new_exception(m, "FirmwareTooOld", x.refused,
                            "The board's firmware predates the feature asked for: reflash it.");
  x.no_reply = new_exception(m, "NoReply", {x.error, PyExc_TimeoutError},
                             "The board stopped answering, or a motion did not end within the time given; every motor "
                             "was sent a stop.");
  x.link_lost = new_exception(m, "LinkLost", {x.error, PyExc_ConnectionError},
                              "The connection to the board failed or was lost (unplugged, the bridge closed, the board "
                              "restarted during a motion).");
  x.port_error = new_exception(m, "PortError", {x.error, PyExc_OSError},
                               "The port could not be opened: missing, busy, no permission (the message says what to do).");
  x.ended_early = new_exception(m, "MotionEndedEarly", x.error,
                                "A motion ended before its end: a limit switch, the emergency switch, a stop, the link "
                                "watchdog, or homing that found no switch. motor, how and position say which and where.");
  x.frame_error = new_exception(m, "FrameError", {x.error, PyExc_ValueError},
                                "The codec refused a frame or command: reason, token, offset (byte), field, expected and "
                                "found, as the board would judge it.");
  x.motion_file_error = new_exception(m, "MotionFileError", {x.error, PyExc_ValueError},
                                      "A motion file with mistakes: errors lists every one (file, line, column, path, "
                                      "expected, found, message); str() gives them one per line.");
  x.profile_error = new_exception(m, "ProfileError", {x.error, PyExc_ValueError},
                                  "A machine profile with mistakes: mistakes lists (line, column, message) for each.");
  x.rounding_warning = new_exception(m, "RoundingWarning", PyExc_UserWarning,
                                     "A value between two steps was rounded to the nearest step.");
}

void raise(py::handle type, const std::string& message, const py::dict& attributes) {
  py::object e = type(message);
  for (auto item : attributes) e.attr(item.first) = item.second;
  PyErr_SetObject(type.ptr(), e.ptr());
  throw py::error_already_set();
}

void raise_session_error(const SessionError& error) {
  const Exceptions& x = exceptions();
  py::dict a;
  a["reason"] = reason_name(error.reason);
  a["code"] = error.reason == proto::Reason::kOk ? py::object(py::none()) : py::int_(static_cast<int>(error.reason));
  a["by_board"] = error.kind == SessionError::Kind::kNak;
  a["token"] = error.nak ? py::object(py::int_(error.nak->token)) : py::object(py::none());
  a["offset"] = error.nak ? py::object(py::int_(error.nak->offset)) : py::object(py::none());
  switch (error.kind) {
    case SessionError::Kind::kInvalid: raise(x.invalid_command, error.message, a);
    case SessionError::Kind::kRefused:
    case SessionError::Kind::kNak: raise(x.refused, error.message, a);
    case SessionError::Kind::kTooOld: raise(x.too_old, error.message, a);
    case SessionError::Kind::kNoReply: raise(x.no_reply, error.message);
    case SessionError::Kind::kLink: raise(x.link_lost, error.message);
    case SessionError::Kind::kInterrupted: raise(PyExc_KeyboardInterrupt, error.message);
    case SessionError::Kind::kEnded: raise(x.ended_early, error.message);
  }
  raise(x.error, error.message);
}

py::dict diagnostic_attributes(const Diagnostic& d) {
  py::dict a;
  a["reason"] = reason_name(d.reason);
  a["code"] = static_cast<int>(d.reason);
  a["token"] = d.token == kNoToken ? py::object(py::none()) : py::object(py::int_(d.token));
  a["offset"] = d.offset;
  a["field"] = d.field;
  a["expected"] = d.expected;
  a["found"] = d.found;
  return a;
}

void raise_diagnostic(const Diagnostic& d, const std::string& input) {
  py::dict a = diagnostic_attributes(d);
  a["input"] = input;
  raise(exceptions().frame_error, std::string(proto::reason_spec(d.reason).name) + ": " + d.message, a);
}

void warn_rounding(const std::vector<std::string>& notes) {
  if (notes.empty()) return;
  py::object warn = py::module_::import("warnings").attr("warn");
  for (const std::string& note : notes) warn(note, exceptions().rounding_warning, 2);
}

void warn_rounding(const std::vector<motion::FileError>& notes) {
  std::vector<std::string> texts;
  for (const motion::FileError& n : notes) texts.push_back(n.text());
  warn_rounding(texts);
}

void raise_profile_error(const ProfileError& e) {
  py::list mistakes;
  for (const ProfileMistake& m : e.mistakes) mistakes.append(py::make_tuple(m.place.line, m.place.column, m.message));
  py::dict a;
  a["path"] = e.path;
  a["mistakes"] = mistakes;
  raise(e.unreadable ? exceptions().port_error : exceptions().profile_error, e.text(), a);
}

void raise_motion_file_error(const std::vector<motion::FileError>& errors) {
  std::vector<MistakeRecord> mistakes;
  std::string text;
  for (const motion::FileError& e : errors) {
    mistakes.push_back({e.where.file, e.where.line, e.where.column, e.where.path, e.expected, e.found, e.message});
    text += (text.empty() ? "" : "\n") + e.text();
  }
  py::dict a;
  a["errors"] = py::cast(mistakes);
  raise(exceptions().motion_file_error, text, a);
}

}  // namespace hmc::python
