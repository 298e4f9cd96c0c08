// The `hmc` Python module: libhmc for scripts (docs/python.md). Boards (board.h), quantities with
// units, the codec's encode/decode with its diagnostics, motion files checked and planned.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstdio>
#include <filesystem>

#include "board.h"
#include "hmc/motion_file.h"
#include "hmc/motion_plan.h"
#include "hmc/units.h"
#include "records.h"

namespace hmc::python {
namespace {

struct ActionRecord {
  size_t index = 0;
  std::string kind;  // home, move, servo, led, wait, stop
  std::string description;
  double start_s = 0;
  double end_s = 0;
  uint32_t line = 0;
  uint32_t column = 0;
  bool estimated = false;
};

struct TrackRecord {
  std::string name;
  uint32_t motor = 1;
  uint32_t microstep = 16;
  int64_t start_position = 0;
  int64_t end_position = 0;
  std::vector<double> t;         // seconds
  std::vector<double> velocity;  // steps/s, signed; piecewise linear between the points
  std::vector<double> stage_boundaries_s;
};

struct PlanRecord {
  motion::Plan plan;
  std::string title;
  double duration_s() const { return plan.duration_s; }
  std::vector<ActionRecord> actions() const {
    static const char* const kinds[] = {"home", "move", "servo", "led", "wait", "stop"};
    std::vector<ActionRecord> out;
    for (const motion::Action& a : plan.actions) {
      out.push_back({a.index, kinds[static_cast<size_t>(a.kind)], a.description, a.start_s, a.end_s, a.where.line,
                     a.where.column, a.estimated});
    }
    return out;
  }
  std::vector<TrackRecord> tracks() const {
    std::vector<TrackRecord> out;
    for (const motion::MotorTrack& t : plan.tracks) {
      TrackRecord r{t.name, t.motor, t.microstep, t.start_position, t.end_position, {}, {}, t.stage_boundaries_s};
      for (const motion::VelocityPoint& p : t.velocity) {
        r.t.push_back(p.t_s);
        r.velocity.push_back(p.velocity);
      }
      out.push_back(std::move(r));
    }
    return out;
  }
};

// Fields listed once: readable attributes, a repr naming them, and equality over them.
template <typename T>
class Record {
 public:
  Record(py::module_& m, const char* name, const char* doc) : class_(m, name, doc), name_(name) {}
  template <typename V>
  Record& field(const char* field, V T::*member, const char* doc) {
    class_.def_readonly(field, member, doc);
    fields_.push_back(field);
    return *this;
  }
  py::class_<T>& done() {
    std::vector<std::string> fields = fields_;
    std::string name = name_;
    class_.def("__repr__", [fields, name](py::object self) {
      std::string text = name + "(";
      for (size_t i = 0; i < fields.size(); ++i) {
        text += (i ? ", " : "") + fields[i] + "=" + py::repr(self.attr(fields[i].c_str())).cast<std::string>();
      }
      return text + ")";
    });
    class_.def("__eq__", [fields](py::object self, py::object other) {
      if (!py::isinstance(other, py::type::of(self))) return false;
      for (const std::string& f : fields) {
        if (!self.attr(f.c_str()).equal(other.attr(f.c_str()))) return false;
      }
      return true;
    });
    class_.attr("__hash__") = py::none();
    return class_;
  }

 private:
  py::class_<T> class_;
  std::string name_;
  std::vector<std::string> fields_;
};

PyQuantity make_quantity(double value, Unit unit) { return PyQuantity{Quantity{value, unit, Dimension::kPosition}}; }

PyQuantity per_second(const PyQuantity& q) {
  if (q.quantity.dimension == Dimension::kAcceleration) raise(exceptions().invalid_command, q.text() + " is already an acceleration");
  PyQuantity out = q;
  out.quantity.dimension = static_cast<Dimension>(static_cast<int>(q.quantity.dimension) + 1);
  return out;
}

std::string quantity_repr(const PyQuantity& q) {
  char number[40];
  std::snprintf(number, sizeof number, "%.17g", q.quantity.value);
  std::string text = std::string("hmc.") + unit_name(q.quantity.unit) + "(" + number + ")";
  if (q.quantity.dimension == Dimension::kSpeed) text += ".per_s()";
  if (q.quantity.dimension == Dimension::kAcceleration) text += ".per_s().per_s()";
  return text;
}

std::string encode_command(const py::args& args, bool crc) {
  const proto::ChecksumMode mode = crc ? proto::ChecksumMode::kCrc16 : proto::ChecksumMode::kSum;
  if (args.size() == 0) raise(PyExc_TypeError, "encode takes a command: encode('STM', 1, 1, 128, 1000, 500) or encode('[#SVM#1#135]')");
  std::vector<std::string> words;
  for (py::handle a : args) {
    if (py::isinstance<py::bool_>(a)) raise(PyExc_TypeError, "command values are whole numbers, not bools");
    words.push_back(py::str(a).cast<std::string>());
  }
  const std::string input = words.size() == 1 ? words[0] : words[0] + " ...";
  Result<Command, Diagnostic> command = words.size() == 1 ? command_from_text(words[0], mode) : command_from_words(words);
  if (!command) raise_diagnostic(command.error(), input);
  Result<std::string, Diagnostic> frame = encode(*command, mode);
  if (!frame) raise_diagnostic(frame.error(), input);
  return *frame;
}

FrameRecord decode_line(const std::string& line, bool board, bool crc) {
  const proto::ChecksumMode mode = crc ? proto::ChecksumMode::kCrc16 : proto::ChecksumMode::kSum;
  if (board) {
    Result<BoardFrame, Diagnostic> frame = decode_board_frame(line, mode);
    if (!frame) raise_diagnostic(frame.error(), line);
    return board_frame_record(*frame, mode);
  }
  Result<Decoded, Diagnostic> decoded = decode(line, mode);
  if (!decoded) raise_diagnostic(decoded.error(), line);
  return command_record(*decoded, mode);
}

PlanRecord plan_file(const std::filesystem::path& file_path, const std::optional<std::filesystem::path>& profile_path,
                     const std::string& firmware, uint32_t baud) {
  const std::string path = file_path.string();
  if (firmware != "v2" && firmware != "seed") raise(exceptions().invalid_command, "firmware is 'v2' or 'seed', not '" + firmware + "'");
  std::optional<Profile> profile;
  if (profile_path) {
    Result<Profile, ProfileError> loaded = load_profile(profile_path->string());
    if (!loaded) raise_profile_error(loaded.error());
    profile = std::move(*loaded);
  }
  motion::ReadOptions read;
  if (profile) {
    read.profile = &*profile;
    read.profile_chosen_by = "profile=";
  }
  Result<motion::MotionFile, std::vector<motion::FileError>> file = motion::load_motion_file(path, read);
  if (!file) raise_motion_file_error(file.error());
  warn_rounding(file->notes);
  motion::PlanOptions options;
  options.firmware = firmware == "seed" ? motion::TargetFirmware::kSeed : motion::TargetFirmware::kV2;
  options.baud = baud;
  auto plan = motion::plan_motion(*file, options);
  if (!plan) raise_motion_file_error(plan.error());
  return PlanRecord{std::move(*plan), file->name.empty() ? path : file->name};
}

// board.events(timeout): each event as it comes; ends when none came within `timeout` seconds.
struct EventIterator {
  Board* board;
  std::optional<double> timeout_s;
};

}  // namespace

void define_module(py::module_& m) {
  m.doc() =
      "The Hybrid Motor Controller from Python: boards (real, over TCP, or simulated with sim://), moves in the "
      "machine profile's units, status, events, motion files, and the protocol's codec. docs/python.md.";
  m.attr("__version__") = HMC_VERSION;
  make_exceptions(m);

  // ---- quantities -----------------------------------------------------------------------
  py::class_<PyQuantity>(m, "Quantity", "A number with a unit: hmc.mm(250), hmc.deg(-90), hmc.mm(20).per_s().")
      .def_property_readonly("value", [](const PyQuantity& q) { return q.quantity.value; })
      .def_property_readonly("unit", [](const PyQuantity& q) { return std::string(unit_name(q.quantity.unit)); },
                             "mm, deg, rev or steps")
      .def_property_readonly("dimension", [](const PyQuantity& q) { return std::string(dimension_words(q.quantity.dimension)); },
                             "'a position', 'a speed' or 'an acceleration'")
      .def("per_s", &per_second, "This quantity per second: a position becomes a speed, a speed an acceleration.")
      .def("__neg__", [](const PyQuantity& q) { return PyQuantity{Quantity{-q.quantity.value, q.quantity.unit, q.quantity.dimension}}; })
      .def("__str__", &PyQuantity::text)
      .def("__repr__", &quantity_repr)
      .def("__eq__", [](const PyQuantity& a, const PyQuantity& b) {
        return a.quantity.value == b.quantity.value && a.quantity.unit == b.quantity.unit && a.quantity.dimension == b.quantity.dimension;
      });
  m.def("mm", [](double v) { return make_quantity(v, Unit::kMm); }, py::arg("value"), "Millimetres (linear axes).");
  m.def("deg", [](double v) { return make_quantity(v, Unit::kDeg); }, py::arg("value"), "Degrees (rotary axes).");
  m.def("rev", [](double v) { return make_quantity(v, Unit::kRev); }, py::arg("value"), "Turns of the axis's output.");
  m.def("steps", [](double v) { return make_quantity(v, Unit::kSteps); }, py::arg("value"), "Motor steps at the axis's microstep.");
  m.def(
      "quantity",
      [](const std::string& text) {
        Result<Quantity> q = parse_quantity(text);
        if (!q) raise(exceptions().invalid_command, q.error().message);
        return PyQuantity{*q};
      },
      py::arg("text"), "A quantity from text: '250mm', '-90deg', '20mm/s', '100mm/s2'.");

  // ---- records --------------------------------------------------------------------------
  Record<MotorRecord>(m, "Motor", "One motor's state. position/target in steps at its microstep; units in the profile axis's unit.")
      .field("motor", &MotorRecord::motor, "1-3")
      .field("state", &MotorRecord::state, "idle, moving, homing, changing, self_test")
      .field("position", &MotorRecord::position, "steps at the motor's microstep, as `hmc move` counts them")
      .field("target", &MotorRecord::target, "where the move ends, in steps")
      .field("board_position", &MotorRecord::board_position, "the board's exact position, 1/256 full step")
      .field("microstep", &MotorRecord::microstep, "1, 2, 4 ... 256")
      .field("rate", &MotorRecord::rate, "steps/s now")
      .field("homed", &MotorRecord::homed, "homed or zeroed since power-up: its position means something")
      .field("endless", &MotorRecord::endless, "runs until stopped")
      .field("switch_reverse", &MotorRecord::switch_reverse, "the limit switch at the reverse end is pressed")
      .field("switch_forward", &MotorRecord::switch_forward, "the limit switch at the forward end is pressed")
      .field("last_end", &MotorRecord::last_end, "how its last motion ended: completed, stopped, limit, emergency, dropped, watchdog")
      .field("axis", &MotorRecord::axis, "the profile's axis on this motor, or None")
      .field("unit", &MotorRecord::unit, "mm or deg (profile axes)")
      .field("units", &MotorRecord::units, "position in the axis's unit (profile axes)")
      .field("target_units", &MotorRecord::target_units, "target in the axis's unit")
      .field("rate_units", &MotorRecord::rate_units, "rate in the axis's unit per second")
      .done();
  Record<ServoRecord>(m, "Servo", "A servo's pulse.")
      .field("servo", &ServoRecord::servo, "1 pan, 2 tilt")
      .field("pulse_us", &ServoRecord::pulse_us, "pulse width in us; 0 released")
      .done();
  Record<StripRecord>(m, "Strip", "An LED strip's colour.")
      .field("strip", &StripRecord::strip, "1 or 2")
      .field("r", &StripRecord::r, "0-255")
      .field("g", &StripRecord::g, "0-255")
      .field("b", &StripRecord::b, "0-255")
      .field("w", &StripRecord::w, "0-255")
      .field("colour", &StripRecord::colour, "'#rrggbbww'")
      .done();
  Record<StatusRecord>(m, "Status", "The board's state, read when status() was called.")
      .field("board", &StatusRecord::board, "which board, in words")
      .field("firmware", &StatusRecord::firmware, "'v2' (ours) or 'seed' (reports nothing: what this session sent)")
      .field("reported", &StatusRecord::reported, "the values came from the board")
      .field("emergency", &StatusRecord::emergency, "the emergency switch is pressed")
      .field("motors", &StatusRecord::motors, "motors 1-3 (index 0-2)")
      .field("servos", &StatusRecord::servos, "servos 1-2")
      .field("strips", &StatusRecord::strips, "strips 1-2")
      .field("watchdog_ms", &StatusRecord::watchdog_ms, "the link watchdog's timeout, 0 off; None: the board has none")
      .field("watchdog_fired", &StatusRecord::watchdog_fired, "the watchdog braked the motors since it was last armed")
      .field("last_reset", &StatusRecord::last_reset, "why the board last reset, in words (protocol 4)")
      .done();
  Record<EventRecord>(m, "Event", "Something the board reported unprompted.")
      .field("kind", &EventRecord::kind, "move_done, watchdog, homed, limit, emergency, driver_fault, booted, reset")
      .field("motor", &EventRecord::motor, "the motor, or None")
      .field("how", &EventRecord::how, "move_done/watchdog: completed, stopped, limit, emergency, dropped, watchdog")
      .field("position", &EventRecord::position, "steps at the motor's microstep")
      .field("board_position", &EventRecord::board_position, "1/256 full step")
      .field("pressed", &EventRecord::pressed, "limit, emergency: pressed (True) or released")
      .field("end", &EventRecord::end, "limit: 0 the reverse end, 1 the forward end")
      .field("homed", &EventRecord::homed, "homed: whether the switch was found")
      .field("text", &EventRecord::text, "in words")
      .field("line", &EventRecord::line, "the frame as it came")
      .field("time", &EventRecord::time, "time.monotonic() when it was read")
      .done();
  Record<FrameRecord>(m, "Frame", "A frame decoded: the command (or board frame), its values and its canonical form.")
      .field("name", &FrameRecord::name, "STM, SVM, ... (board frames: ACK, NAK, STA, EVD, ...)")
      .field("event", &FrameRecord::event, "a board frame sent unprompted")
      .field("values", &FrameRecord::values, "field name -> value, in wire order")
      .field("description", &FrameRecord::description, "in words")
      .field("frame", &FrameRecord::frame, "the canonical frame")
      .field("canonical", &FrameRecord::canonical, "the input was already canonical")
      .field("warnings", &FrameRecord::warnings, "values the spec advises against")
      .done();
  Record<ProgressRecord>(m, "Progress", "run_file()'s progress: an action started or done.")
      .field("kind", &ProgressRecord::kind, "started, done, returning")
      .field("step", &ProgressRecord::step, "the action, 1-based")
      .field("total", &ProgressRecord::total, "actions in the plan")
      .field("description", &ProgressRecord::description, "what it does")
      .field("elapsed_s", &ProgressRecord::elapsed_s, "since the run began")
      .field("remaining_s", &ProgressRecord::remaining_s, "planned time left")
      .done();
  Record<MistakeRecord>(m, "Mistake", "One mistake in a motion file.")
      .field("file", &MistakeRecord::file, "the file")
      .field("line", &MistakeRecord::line, "1-based; 0 the file as a whole")
      .field("column", &MistakeRecord::column, "1-based, in bytes")
      .field("path", &MistakeRecord::path, "JSON path: $.steps[3].move.speed")
      .field("expected", &MistakeRecord::expected, "what was expected")
      .field("found", &MistakeRecord::found, "what was found")
      .field("message", &MistakeRecord::message, "the sentence shown to people")
      .done()
      .def("__str__", [](const MistakeRecord& r) {
        motion::FileError e{{r.file, r.line, r.column, r.path}, r.expected, r.found, r.message};
        return e.text();
      });
  Record<ActionRecord>(m, "Action", "One planned action (repeats unrolled).")
      .field("index", &ActionRecord::index, "1-based")
      .field("kind", &ActionRecord::kind, "home, move, servo, led, wait, stop")
      .field("description", &ActionRecord::description, "in words, or the step's label")
      .field("start_s", &ActionRecord::start_s, "planned start")
      .field("end_s", &ActionRecord::end_s, "planned end")
      .field("line", &ActionRecord::line, "its step's line in the file")
      .field("column", &ActionRecord::column, "and column")
      .field("estimated", &ActionRecord::estimated, "end_s is a guess (homing)")
      .done();
  Record<TrackRecord>(m, "Track", "One motor's planned velocity over time: plot t against velocity.")
      .field("name", &TrackRecord::name, "the motor's name in the file")
      .field("motor", &TrackRecord::motor, "1-3")
      .field("microstep", &TrackRecord::microstep, "its microstep")
      .field("start_position", &TrackRecord::start_position, "steps")
      .field("end_position", &TrackRecord::end_position, "steps")
      .field("t", &TrackRecord::t, "seconds from the start")
      .field("velocity", &TrackRecord::velocity, "steps/s, signed, at each t (linear in between)")
      .field("stage_boundaries_s", &TrackRecord::stage_boundaries_s, "when each stage of a staged profile begins")
      .done();
  py::class_<PlanRecord>(m, "Plan", "A motion file planned: its actions, each motor's velocity, the total time.")
      .def_property_readonly("duration_s", &PlanRecord::duration_s)
      .def_property_readonly("actions", &PlanRecord::actions)
      .def_property_readonly("tracks", &PlanRecord::tracks)
      .def("svg", [](const PlanRecord& p, std::optional<std::string> title) { return motion::plot_svg(p.plan, title.value_or(p.title)); },
           py::arg("title") = py::none(), "Velocity over time as an SVG picture, one panel per motor.")
      .def("csv", [](const PlanRecord& p) { return motion::plot_csv(p.plan); }, "t_s,motor,name,velocity rows.")
      .def("__repr__", [](const PlanRecord& p) {
        return "<hmc.Plan " + std::to_string(p.plan.actions.size()) + " actions, " + number_text(p.plan.duration_s) + " s>";
      });

  // ---- frames and motion files ----------------------------------------------------------
  m.def("encode", &encode_command, py::kw_only(), py::arg("crc") = false,
        "The canonical frame of a command, length and checksum filled in: encode('STM', 1, 1, 128, 1000, 500), "
        "encode('[#SVM#1#135]'), encode('SVM 1 135'), or a frame to re-encode. crc=True writes the CRC-16 checksum. "
        "Raises FrameError with the codec's diagnostic.");
  m.def("decode", &decode_line, py::arg("line"), py::kw_only(), py::arg("board") = false, py::arg("crc") = false,
        "Judges one line as the board does and returns a Frame; board=True reads a frame the board sends (ACK, NAK, "
        "STA, EVD, ...). Raises FrameError naming the reason, token, byte offset, field, expected and found.");
  m.def(
      "check",
      [](const std::filesystem::path& path, const std::optional<std::filesystem::path>& profile) {
        return plan_file(path, profile, "v2", kDefaultBaud);
      },
      py::arg("path"), py::kw_only(), py::arg("profile") = py::none(),
      "Validates (and plans) a motion file; raises MotionFileError carrying every mistake with line and column. "
      "profile: the machine profile for a file that names none and declares no motors.");
  m.def("plan", &plan_file, py::arg("path"), py::kw_only(), py::arg("profile") = py::none(), py::arg("firmware") = "v2",
        py::arg("baud") = kDefaultBaud,
        "Plans a motion file: the timeline (actions) and each motor's velocity samples (tracks). profile: as for "
        "check().");

  // ---- boards ---------------------------------------------------------------------------
  py::class_<EventIterator>(m, "EventIterator", "Events as they come (board.events()).")
      .def("__iter__", [](EventIterator& it) -> EventIterator& { return it; })
      .def("__next__", [](EventIterator& it) {
        std::optional<EventRecord> e = it.board->next_event(it.timeout_s);
        if (!e) throw py::stop_iteration();
        return *e;
      });

  py::class_<Board>(m, "Board",
                    "One board, opened by hmc.open(). Use it in a with block: leaving it stops the motors this Board set "
                    "moving, except those started with keep_running=True. Every wait releases the GIL and is ended by "
                    "Ctrl-C, which stops every motor first and raises KeyboardInterrupt.")
      .def_property_readonly("description", &Board::description, "which board: 'simulated board sim://x (real time)'")
      .def_property_readonly("firmware", &Board::firmware, "the firmware's version ('0.1.0'), or 'seed'")
      .def_property_readonly("protocol", &Board::protocol, "the protocol version the board speaks (None for the seed)")
      .def_property_readonly("simulated", &Board::simulated, "the board is sim://, in this process")
      .def_property_readonly("watchdog_armed", &Board::watchdog_armed, "the link watchdog is armed and kept alive")
      .def_property_readonly("axes", &Board::profile_axes, "the profile's axis names")
      .def_property_readonly("closed", &Board::closed)
      .def("move", &Board::move, py::arg("axis"), py::kw_only(), py::arg("to") = py::none(), py::arg("by") = py::none(),
           py::arg("steps") = py::none(), py::arg("speed") = py::none(), py::arg("accel") = py::none(),
           py::arg("wait") = true, py::arg("keep_running") = false, py::arg("timeout") = py::none(),
           "Moves an axis (1-3 or a profile name) to= a position or by= a distance (numbers in the profile axis's unit, "
           "else steps; or hmc.mm(250), '250mm'), or steps= at its microstep. speed= and accel= likewise (default: the "
           "profile's, else 500 us per step and the board's acceleration). wait=True returns the Motor once it rests "
           "and raises MotionEndedEarly if it stopped short; wait=False returns at once.")
      .def("run", &Board::run, py::arg("axis"), py::arg("rate"), py::kw_only(), py::arg("accel") = py::none(),
           py::arg("keep_running") = false,
           "Runs an axis until stopped at rate (steps/s, or the axis's unit/s; negative: reverse). keep_running=True "
           "leaves it running when the Board closes.")
      .def("stop", &Board::stop, py::arg("axis") = py::none(),
           "Stops one axis, a list of them, or all (None), and waits until they rest (a ramped motor brakes).")
      .def("home", &Board::home, py::arg("axis") = py::none(),
           "Homes an axis against its limit switch, or every motor with switches (None), one after another, as the "
           "profile's homing says. Raises MotionEndedEarly when the switch was not found.")
      .def("step_budgets", &Board::step_budgets,
           "The step-rate budgets of the moving motors together, (constant, ramping) steps/s, as the board reports "
           "them (protocol 7); FirmwareTooOld before.")
      .def("zero", &Board::zero, py::arg("axis"), py::arg("position") = 0,
           "Tells the board the resting axis is at position (default 0) from now on (protocol 6).")
      .def("wait", &Board::wait, py::arg("axis") = py::none(), py::arg("timeout") = py::none(),
           "Waits until the axis (or all) rests; NoReply after timeout seconds (every motor is then sent a stop); "
           "MotionEndedEarly if a move this Board started ended short.")
      .def("servo", &Board::servo, py::arg("servo"), py::arg("angle"), "Turns servo 1 (pan) or 2 (tilt) to 10-170 degrees.")
      .def("led", &Board::led, py::arg("strip"), py::arg("colour"),
           "Sets strip 1 or 2 to '#RRGGBB', '#RRGGBBWW', 'off' or (r, g, b[, w]).")
      .def("status", &Board::status, "Reads every unit's state from the board and returns a Status.")
      .def("send", &Board::send, py::arg("command"), py::kw_only(), py::arg("raw") = false,
           "Sends one command (a frame, '[#SVM#1#135]' or 'SVM 1 135'), checked like every other, and returns the "
           "board's reply as a Frame. raw=True sends the line unchanged and unchecked (to see the board refuse).")
      .def("arm_watchdog", &Board::arm_watchdog, py::arg("timeout"),
           "Arms the board's link watchdog (seconds, protocol 3); the library keeps the link alive from a thread.")
      .def("disarm_watchdog", &Board::disarm_watchdog)
      .def("on_event", &Board::on_event, py::arg("callback"),
           "Calls callback(event) for each event the board reports, on the thread inside a board call: while it waits "
           "(every few tens of ms) or as the call returns. The callback may not call the board; an exception it "
           "raises ends the wait, stops every motor, and is raised by the call.")
      .def(
          "events", [](Board& b, std::optional<double> timeout) { return EventIterator{&b, timeout}; },
          py::arg("timeout") = py::none(), py::keep_alive<0, 1>(),
          "Iterates over events, oldest first (up to 1000 kept since the board opened), reading the board while none "
          "is waiting; ends when none came within timeout seconds (None: never).")
      .def("listen", &Board::listen, py::arg("seconds"), "Reads the board for seconds, running on_event callbacks.")
      .def("run_file",
           [](Board& b, const std::filesystem::path& path, py::object progress, size_t start_at,
              const Board::StartPositions& at) { return b.run_file(path.string(), std::move(progress), start_at, at); },
           py::arg("path"), py::kw_only(), py::arg("progress") = py::none(), py::arg("start_at") = 1,
           py::arg("at") = py::none(),
           "Validates, plans and runs a motion file, calling progress(Progress) as actions start and end; start_at "
           "resumes at that action. at=(p1, p2, p3): where motors 1-3 were (steps, a fraction between two; None unknown) when the file first "
           "started, as an interrupted run's status said: the motors first go where the plan has them at start_at "
           "(hmc run --from K --at). Returns the actions completed.")
      .def("close", &Board::close, "Stops the motors this Board set moving (unless keep_running) and closes the port.")
      .def("__enter__", [](Board& b) -> Board& { return b; })
      .def("__exit__", [](Board& b, py::object type, py::object, py::object) {
        try {
          b.close();
        } catch (py::error_already_set&) {
          if (type.is_none()) throw;  // the with block's own exception is the one to see
        }
        return false;
      })
      .def("__repr__", [](const Board& b) { return "<hmc.Board " + b.description() + ">"; });

  m.def(
      "open",
      [](std::optional<std::string> port, std::optional<std::filesystem::path> profile, std::optional<uint32_t> baud,
         double timeout, const std::string& firmware, double watchdog) {
        const std::optional<std::string> profile_path = profile ? std::optional<std::string>(profile->string()) : std::nullopt;
        return Board::open(OpenOptions{port, profile_path, baud, timeout, firmware, watchdog});
      },
      py::arg("port") = py::none(), py::arg("profile") = py::none(), py::kw_only(), py::arg("baud") = py::none(),
      py::arg("timeout") = 1.0, py::arg("firmware") = "auto", py::arg("watchdog") = 0.5,
      "Opens a board: '/dev/ttyUSB0', 'tcp://HOST:PORT', a pseudo-terminal, or 'sim://NAME?fresh' (the simulated "
      "board, in this process). profile: a machine profile (TOML) for axis names and units. timeout: seconds to wait "
      "for each reply. firmware: 'auto', 'v2' or 'seed'. watchdog: the link watchdog's timeout in seconds, armed "
      "and kept alive while the Board is open (0: none; never for sim://). Default port: the profile's, HMC_PORT, "
      "else the one FT232R bridge.");
}

}  // namespace hmc::python

PYBIND11_MODULE(hmc, m) { hmc::python::define_module(m); }
