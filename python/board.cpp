// hmc.Board over a Session: axes and units, waits that Ctrl-C interrupts, events, motion files.
#include "board.h"

#include <pybind11/stl.h>

#include <cmath>
#include <cstdlib>

#include "hmc/motion_file.h"
#include "hmc/motion_plan.h"
#include "hmc/motion_runner.h"
#include "hmc/port_list.h"
#include "hmc/transport.h"

namespace hmc::python {
namespace {

constexpr size_t kKeptEvents = 1000;
constexpr Millis kPollEvery{20};
constexpr Millis kListenSlice{50};

double monotonic_now() { return std::chrono::duration<double>(Clock::now().time_since_epoch()).count(); }

[[noreturn]] void invalid(const std::string& message) { raise(exceptions().invalid_command, message); }

Millis millis(double seconds) { return Millis{static_cast<int64_t>(std::llround(seconds * 1000.0))}; }

std::optional<Millis> limit_of(std::optional<double> timeout_s) {
  if (!timeout_s) return std::nullopt;
  if (!(*timeout_s >= 0)) invalid("timeout must be 0 or more seconds, not " + number_text(*timeout_s));
  return millis(*timeout_s);
}

// What a board call brings back besides its value: an error to raise once the GIL is held again.
struct Failure {
  std::optional<SessionError> session;
  std::optional<std::string> usage;    // InvalidCommand
  std::optional<std::string> refused;  // Refused by the host
  std::optional<std::vector<motion::FileError>> file_errors;
  void raise_if_any() const {
    if (session) raise_session_error(*session);
    if (usage) invalid(*usage);
    if (refused) {
      py::dict a;
      a["reason"] = py::none();
      a["code"] = py::none();
      a["by_board"] = false;
      a["token"] = py::none();
      a["offset"] = py::none();
      raise(exceptions().refused, *refused, a);
    }
  }
};

[[noreturn]] void raise_ended_early(uint32_t motor, const std::string& how, const MotorRecord& at, const std::string& message) {
  py::dict a;
  a["motor"] = motor;
  a["how"] = how;
  a["position"] = at.position;
  a["status"] = py::cast(at);
  raise(exceptions().ended_early, message, a);
}

}  // namespace

// ---- opening and closing ------------------------------------------------------------------

std::unique_ptr<Board> Board::open(const OpenOptions& o) {
  std::unique_ptr<Board> board(new Board());
  if (o.profile) {
    Result<Profile, ProfileError> loaded = load_profile(*o.profile);
    if (!loaded) raise_profile_error(loaded.error());
    board->profile_ = std::move(*loaded);
  }
  const Profile* profile = board->profile_ ? &*board->profile_ : nullptr;
  std::string port;
  if (o.port) {
    port = *o.port;
  } else if (profile != nullptr && profile->port) {
    port = *profile->port;
  } else if (const char* env = std::getenv("HMC_PORT"); env != nullptr && *env != '\0') {
    port = env;
  } else {
    Result<std::vector<PortInfo>> ports = list_ports();
    std::optional<std::string> found = ports ? find_board_port(*ports) : std::nullopt;
    if (!found) {
      raise(exceptions().port_error,
            "no port given and not exactly one FT232R bridge found: name it (hmc.open('/dev/ttyUSB0'), HMC_PORT, or the "
            "profile's port); hmc.open('sim://') drives the simulated board");
    }
    port = *found;
  }
  std::string firmware = o.firmware;
  if (firmware == "auto" && profile != nullptr && profile->firmware) firmware = *profile->firmware;
  if (firmware != "auto" && firmware != "v2" && firmware != "seed") invalid("firmware must be 'auto', 'v2' or 'seed', not '" + firmware + "'");
  if (!(o.timeout_s > 0)) invalid("timeout must be above 0 seconds");
  PortOptions port_options;
  port_options.baud = o.baud ? *o.baud : (profile != nullptr && profile->baud ? *profile->baud : kDefaultBaud);

  SessionOptions options;
  options.firmware = firmware == "v2" ? FirmwareChoice::kV2 : firmware == "seed" ? FirmwareChoice::kSeed : FirmwareChoice::kDetect;
  options.reply_timeout = millis(o.timeout_s);
  options.baud = port_options.baud;
  Board* self = board.get();
  options.interrupted = [self] { return self->poll_python(); };
  options.on_line = [self](std::string_view line, const Result<BoardFrame, Diagnostic>& frame) { self->on_line(line, frame); };

  Failure failure;
  std::optional<std::string> port_failure;
  {
    py::gil_scoped_release release;
    Result<std::unique_ptr<Transport>> link = open_port(port, port_options);
    if (!link) {
      port_failure = link.error().message;
    } else if (SessionResult<std::unique_ptr<Session>> session = Session::open(std::move(*link), options); !session) {
      failure.session = session.error();
    } else {
      board->session_ = std::move(*session);
    }
  }
  board->raise_pending();
  if (port_failure) raise(exceptions().port_error, *port_failure);
  failure.raise_if_any();
  board->port_ = port;
  // The profile's soft limits, for the board to enforce too, on axes whose position means something.
  if (profile != nullptr) {
    for (const Axis& axis : profile->axes) {
      std::optional<SoftLimits> limits = soft_limits_command(axis);
      if (!limits) continue;
      board->call([&](Session& s) -> SessionResult<Done> {
        if (s.firmware() != Firmware::kV2 || !s.model().motor(axis.motor).homed) return Done{};
        SessionResult<BoardFrame> sent = s.execute(*limits);
        if (!sent) return sent.error();
        return Done{};
      });
    }
  }
  if (o.watchdog_s > 0 && !board->session_->simulated() && board->session_->supports(proto::Feature::kLinkWatchdog)) {
    board->arm_watchdog(o.watchdog_s);
  }
  return board;
}

Board::~Board() {
  // Collected without close(): still stop what this board started, without calling into Python.
  python_polls_ = false;
  if (session_ == nullptr) return;
  stop_started(false);
  session_.reset();
}

void Board::close() {
  if (session_ == nullptr) return;
  // The port closes even when stopping fails (a lost link): the error is raised after.
  struct Closing {
    Board& board;
    ~Closing() {
      py::gil_scoped_release release;
      std::lock_guard<std::mutex> lock(board.mutex_);
      board.session_.reset();  // disarms the link watchdog, saves a simulated board's state
    }
  } closing{*this};
  stop_started(true);
}

void Board::stop_started(bool python_allowed) {
  if (started_.empty()) return;
  const std::set<uint32_t> motors = started_;
  started_.clear();
  const auto act = [&motors](Session& s) -> SessionResult<Done> {
    if (SessionResult<Done> fresh = s.refresh(); !fresh) return fresh;
    std::vector<uint32_t> moving;
    for (uint32_t m : motors) {
      if (s.model().motor(m).state == MotorState::kIdle) continue;
      if (SessionResult<BoardFrame> sent = s.execute(StepperMove{m, proto::kActionStop, 0, 0, 0}); !sent) return sent.error();
      moving.push_back(m);
    }
    return s.wait_until_idle(moving);
  };
  if (python_allowed) {
    SessionResult<Done> done = call(act);
    if (!done) raise_session_error(done.error());
  } else {
    std::lock_guard<std::mutex> lock(mutex_);
    (void)act(*session_);
  }
}

// ---- calls, polls and events --------------------------------------------------------------

template <typename Act>
auto Board::call(Act&& act) -> decltype(act(std::declval<Session&>())) {
  if (dispatching_ || caller_.load() == std::this_thread::get_id()) {
    raise(PyExc_RuntimeError, "a callback cannot call the board: it runs inside a board call (return, and act after it)");
  }
  if (session_ == nullptr) raise(exceptions().error, "the board is closed");
  std::optional<decltype(act(std::declval<Session&>()))> out;
  {
    py::gil_scoped_release release;
    std::lock_guard<std::mutex> lock(mutex_);
    struct Owner {
      std::atomic<std::thread::id>& caller;
      explicit Owner(std::atomic<std::thread::id>& c) : caller(c) { caller = std::this_thread::get_id(); }
      ~Owner() { caller = std::thread::id{}; }
    } owner(caller_);
    if (session_ != nullptr) out.emplace(act(*session_));
  }
  if (!out) raise(exceptions().error, "the board is closed");
  dispatch_events();
  if (pending_) {
    // A callback raised after the call's own wait ended: stop every motor all the same.
    py::gil_scoped_release release;
    std::lock_guard<std::mutex> lock(mutex_);
    if (session_ != nullptr) (void)session_->stop_all();
  }
  raise_pending();
  return std::move(*out);
}

bool Board::poll_python() {
  if (!python_polls_) return pending_flag_;
  const Clock::time_point now = Clock::now();
  if (now - last_poll_ < kPollEvery) return pending_flag_;
  last_poll_ = now;
  py::gil_scoped_acquire gil;
  dispatch_events();
  if (!pending_ && PyErr_CheckSignals() != 0) pending_.emplace();  // fetches KeyboardInterrupt
  pending_flag_ = pending_.has_value();
  return pending_flag_;
}

void Board::dispatch_events() {
  std::deque<EventRecord> batch;
  {
    std::lock_guard<std::mutex> lock(events_mutex_);
    batch.swap(undispatched_);
  }
  dispatching_ = true;
  for (const EventRecord& e : batch) {
    for (const py::object& callback : callbacks_) {
      try {
        callback(e);
      } catch (py::error_already_set& error) {
        if (!pending_) pending_ = error;
        pending_flag_ = true;
      }
    }
  }
  dispatching_ = false;
}

void Board::raise_pending() {
  if (!pending_) return;
  py::error_already_set error = std::move(*pending_);
  pending_.reset();
  pending_flag_ = false;
  throw error;
}

void Board::on_line(std::string_view line, const Result<BoardFrame, Diagnostic>& frame) {
  if (!frame || !is_event(*frame)) return;
  uint32_t microstep = 256;
  if (session_ != nullptr) {
    uint32_t motor = 0;
    if (const auto* d = std::get_if<MotionEnded>(&*frame)) motor = d->motor;
    if (const auto* h = std::get_if<HomingEnded>(&*frame)) motor = h->motor;
    if (motor >= 1 && motor <= proto::kMotorCount) microstep = session_->model().motor(motor).microstep;
  }
  EventRecord e = event_record(*frame, line, microstep, monotonic_now());
  std::lock_guard<std::mutex> lock(events_mutex_);
  events_.push_back(e);
  if (events_.size() > kKeptEvents) events_.pop_front();
  if (has_callbacks_) undispatched_.push_back(std::move(e));
}

void Board::on_event(py::object callback) {
  if (!PyCallable_Check(callback.ptr())) raise(PyExc_TypeError, "on_event takes a callable: f(event)");
  callbacks_.push_back(std::move(callback));
  has_callbacks_ = true;
}

std::optional<EventRecord> Board::next_event(std::optional<double> timeout_s) {
  const std::optional<Millis> limit = limit_of(timeout_s);
  const Clock::time_point deadline = Clock::now() + limit.value_or(Millis{0});
  for (;;) {
    {
      std::lock_guard<std::mutex> lock(events_mutex_);
      if (!events_.empty()) {
        EventRecord e = std::move(events_.front());
        events_.pop_front();
        return e;
      }
    }
    const Millis left = limit ? std::chrono::duration_cast<Millis>(deadline - Clock::now()) : kListenSlice;
    if (left <= Millis{0}) return std::nullopt;
    SessionResult<Done> heard = call([&](Session& s) { return s.listen(std::min(left, kListenSlice)); });
    if (!heard) raise_session_error(heard.error());
  }
}

void Board::listen(double seconds) {
  SessionResult<Done> heard = call([&](Session& s) { return s.listen(millis(seconds)); });
  if (!heard) raise_session_error(heard.error());
}

// ---- axes and quantities ------------------------------------------------------------------

const Axis* Board::profile_axis(uint32_t motor) const { return profile_ ? profile_->axis_of_motor(motor) : nullptr; }

Axis Board::axis_of(const py::object& axis) const {
  if (py::isinstance<py::bool_>(axis)) raise(PyExc_TypeError, "axis is a motor number 1-3 or an axis name, not a bool");
  if (py::isinstance<py::int_>(axis)) {
    const long motor = axis.cast<long>();
    if (motor < 1 || motor > static_cast<long>(proto::kMotorCount)) invalid("motor must be 1-3, not " + std::to_string(motor));
    if (const Axis* a = profile_axis(static_cast<uint32_t>(motor))) return *a;
    return plain_motor_axis(static_cast<uint32_t>(motor), 0);  // the microstep is the motor's, read in the call
  }
  if (py::isinstance<py::str>(axis)) {
    const std::string name = axis.cast<std::string>();
    if (profile_) {
      if (const Axis* a = profile_->find(name)) return *a;
    }
    if (name.size() == 1 && name[0] >= '1' && name[0] <= '3') return axis_of(py::int_(name[0] - '0'));
    std::string names;
    if (profile_) {
      for (const Axis& a : profile_->axes) names += (names.empty() ? "" : ", ") + a.name;
    }
    invalid("no axis '" + name + "': give a motor 1-3 or an axis name" +
            (names.empty() ? std::string(" (no profile axes: hmc.open(..., profile='config.toml'))") : "; the profile's axes are " + names));
  }
  raise(PyExc_TypeError, "axis is a motor number 1-3 or an axis name");
}

std::vector<uint32_t> Board::motors_of(const py::object& axis) const {
  if (axis.is_none() || (py::isinstance<py::str>(axis) && axis.cast<std::string>() == "all")) return {1, 2, 3};
  if (py::isinstance<py::list>(axis) || py::isinstance<py::tuple>(axis)) {
    std::vector<uint32_t> motors;
    for (py::handle one : axis) motors.push_back(axis_of(py::reinterpret_borrow<py::object>(one)).motor);
    return motors;
  }
  return {axis_of(axis).motor};
}

std::string Board::quantity_text(const py::object& value, const Axis& axis, Dimension dimension, const char* name) const {
  if (py::isinstance<PyQuantity>(value)) return value.cast<const PyQuantity&>().text();
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  if (!py::isinstance<py::bool_>(value) && (py::isinstance<py::int_>(value) || py::isinstance<py::float_>(value))) {
    // A bare number is in the profile axis's own unit, else in steps.
    const Unit unit = profile_axis(axis.motor) != nullptr ? axis.unit() : Unit::kSteps;
    return PyQuantity{Quantity{value.cast<double>(), unit, dimension}}.text();
  }
  raise(PyExc_TypeError, std::string(name) + " takes a number, a quantity (hmc.mm(250)) or a string ('250mm')");
}

// ---- motion -------------------------------------------------------------------------------

MotorRecord Board::move(const py::object& axis, const py::object& to, const py::object& by, const py::object& steps,
                        const py::object& speed, const py::object& accel, bool wait, bool keep_running,
                        std::optional<double> timeout_s) {
  const Axis chosen = axis_of(axis);
  const bool plain = profile_axis(chosen.motor) == nullptr;
  if ((to.is_none() ? 0 : 1) + (by.is_none() ? 0 : 1) + (steps.is_none() ? 0 : 1) != 1) {
    invalid("give the target once: to= (a position), by= (a distance) or steps=");
  }
  UnitMoveRequest request;
  request.names = {"to=", "by=", "speed=", "accel="};
  if (!to.is_none()) request.to = quantity_text(to, chosen, Dimension::kPosition, "to");
  if (!by.is_none()) request.by = quantity_text(by, chosen, Dimension::kPosition, "by");
  if (!steps.is_none()) {
    if (!py::isinstance<py::int_>(steps) || py::isinstance<py::bool_>(steps)) raise(PyExc_TypeError, "steps= takes a whole number of steps");
    request.by = std::to_string(steps.cast<long long>()) + "steps";
    request.names.by = "steps=";
  }
  if (!speed.is_none()) request.speed = quantity_text(speed, chosen, Dimension::kSpeed, "speed");
  if (!accel.is_none()) request.accel = quantity_text(accel, chosen, Dimension::kAcceleration, "accel");
  const std::optional<Millis> limit = limit_of(timeout_s);

  Failure failure;
  std::vector<std::string> notes;
  bool moved = false;
  const uint32_t m = chosen.motor;
  MotorStatus motor = call([&](Session& s) {
    Axis a = chosen;
    if (plain) a.microstep = s.model().motor(m).microstep;
    Result<UnitMove> planned = unit_move(a, s.model().motor(m), request);
    if (!planned) {
      failure.usage = planned.error().message;
      return s.model().motor(m);
    }
    if (std::optional<std::string> beyond = beyond_soft_limits(a, s.model().motor(m), planned->target)) {
      failure.refused = *beyond;
      return s.model().motor(m);
    }
    notes = planned->notes;
    if (!planned->move) return s.model().motor(m);  // already there
    StepperMove step_move = *planned->move;
    if (!planned->delay_us) step_move.delay_us = kDefaultMoveDelayUs;
    if (planned->accel) {
      if (s.firmware() == Firmware::kSeed) {
        failure.refused = "the seed firmware has no acceleration: move at a constant rate, or plan a staged ramp in a motion file";
        return s.model().motor(m);
      }
      if (SessionResult<BoardFrame> set = s.execute(SetSetting{m, proto::kSettingAccel, *planned->accel}); !set) {
        failure.session = set.error();
        return s.model().motor(m);
      }
    }
    if (SessionResult<BoardFrame> sent = s.execute(step_move); !sent) {
      failure.session = sent.error();
      return s.model().motor(m);
    }
    moved = true;
    if (wait) {
      if (SessionResult<Done> done = s.wait_until_idle({m}, limit); !done) failure.session = done.error();
    }
    return s.model().motor(m);
  });
  warn_rounding(notes);
  failure.raise_if_any();
  if (moved && !wait) {
    if (keep_running) {
      started_.erase(m);
    } else {
      started_.insert(m);
    }
  }
  const std::optional<MotionEnd> end = session_->model().last_end[m - 1];
  const MotorRecord record = motor_record(motor, moved && wait ? end : std::nullopt, profile_axis(m));
  if (moved && wait && end && *end != MotionEnd::kCompleted) {
    raise_ended_early(m, motion_end_name(*end), record,
                      "motor " + std::to_string(m) + "'s move ended early: " + motion_end_name(*end) + ", at " +
                          std::to_string(record.position) + " steps");
  }
  return record;
}

void Board::run(const py::object& axis, const py::object& rate, const py::object& accel, bool keep_running) {
  const Axis chosen = axis_of(axis);
  const bool plain = profile_axis(chosen.motor) == nullptr;
  const std::string rate_text = quantity_text(rate, chosen, Dimension::kSpeed, "rate");
  const std::optional<std::string> accel_text =
      accel.is_none() ? std::nullopt : std::optional<std::string>(quantity_text(accel, chosen, Dimension::kAcceleration, "accel"));
  Result<Quantity> quantity = parse_quantity(rate_text);
  if (!quantity) invalid("rate=: " + quantity.error().message);
  Failure failure;
  std::vector<std::string> notes;
  const uint32_t m = chosen.motor;
  call([&](Session& s) -> int {
    Axis a = chosen;
    if (plain) a.microstep = s.model().motor(m).microstep;
    Result<StepCount> steps = a.to_steps(*quantity, Dimension::kSpeed);
    if (!steps) {
      failure.usage = "rate=: " + steps.error().message;
      return 0;
    }
    if (std::fabs(steps->exact) < 1e-9) {
      failure.usage = "rate= must not be 0: stop() stops a motor";
      return 0;
    }
    const auto delay = static_cast<uint32_t>(std::max(1.0, std::round(1e6 / std::fabs(steps->exact))));
    const StepperMove endless{m, steps->exact < 0 ? proto::kActionReverse : proto::kActionForward, a.microstep, 0, delay};
    if (accel_text) {
      Result<uint32_t> per_s2 = accel_steps(a, *accel_text, notes, "accel=");
      if (!per_s2) {
        failure.usage = per_s2.error().message;
        return 0;
      }
      if (SessionResult<BoardFrame> set = s.execute(SetSetting{m, proto::kSettingAccel, *per_s2}); !set) {
        failure.session = set.error();
        return 0;
      }
    }
    if (SessionResult<BoardFrame> sent = s.execute(endless); !sent) failure.session = sent.error();
    return 0;
  });
  warn_rounding(notes);
  failure.raise_if_any();
  if (keep_running) {
    started_.erase(m);
  } else {
    started_.insert(m);
  }
}

void Board::stop(const py::object& axis) {
  const bool all = axis.is_none() || (py::isinstance<py::str>(axis) && axis.cast<std::string>() == "all");
  const std::vector<uint32_t> motors = motors_of(axis);
  SessionResult<Done> done = call([&](Session& s) -> SessionResult<Done> {
    if (all) {
      if (SessionResult<Done> stopped = s.stop_all(); !stopped) return stopped;
    } else {
      for (uint32_t m : motors) {
        if (SessionResult<BoardFrame> sent = s.execute(StepperMove{m, proto::kActionStop, 0, 0, 0}); !sent) return sent.error();
      }
    }
    return s.wait_until_idle(motors);  // a motor with an acceleration brakes
  });
  for (uint32_t m : motors) started_.erase(m);
  if (!done) raise_session_error(done.error());
}

void Board::home(const py::object& axis) {
  const bool all = axis.is_none() || (py::isinstance<py::str>(axis) && axis.cast<std::string>() == "all");
  std::vector<uint32_t> motors = all ? std::vector<uint32_t>{} : motors_of(axis);
  Failure failure;
  std::optional<uint32_t> not_homed;
  std::string why;
  const std::optional<Profile>& profile = profile_;
  MotorStatus last = call([&](Session& s) {
    if (all) {
      for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
        const bool has = s.version() ? ((s.version()->switch_mask >> (m - 1)) & 1u) != 0 : proto::motor_has_switches(m);
        if (has) motors.push_back(m);
      }
    }
    // Homing needs every motor at rest (seed rule [2]): one after another; the first that fails ends it.
    for (uint32_t m : motors) {
      StepperMove homing{m, proto::kActionHome, 0, 0, 0};
      const Axis* a = profile ? profile->axis_of_motor(m) : nullptr;
      if (a != nullptr) {
        const HomingSetup setup = homing_setup(*a, homing);
        for (const SetSetting& set : setup.settings) {
          if (SessionResult<BoardFrame> done = s.execute(set); !done) {
            failure.session = done.error();
            return s.model().motor(m);
          }
        }
        homing = setup.move;
      }
      if (SessionResult<BoardFrame> sent = s.execute(homing); !sent) {
        failure.session = sent.error();
        return s.model().motor(m);
      }
      if (SessionResult<Done> done = s.wait_until_idle({m}); !done) {
        failure.session = done.error();
        return s.model().motor(m);
      }
      if (s.firmware() == Firmware::kV2 && !s.model().motor(m).homed) {
        not_homed = m;
        why = s.model().board.emergency ? "the emergency switch stopped it" : "the switch was not found";
        return s.model().motor(m);
      }
      if (a != nullptr) {
        if (std::optional<SoftLimits> limits = soft_limits_command(*a); limits && s.firmware() == Firmware::kV2) {
          if (SessionResult<BoardFrame> sent = s.execute(*limits); !sent) {
            failure.session = sent.error();
            return s.model().motor(m);
          }
        }
      }
    }
    return motors.empty() ? MotorStatus{} : s.model().motor(motors.back());
  });
  failure.raise_if_any();
  if (not_homed) {
    raise_ended_early(*not_homed, "not_homed", motor_record(last, std::nullopt, profile_axis(*not_homed)),
                      "motor " + std::to_string(*not_homed) + " not homed: " + why);
  }
}

MotorRecord Board::zero(const py::object& axis, const py::object& position) {
  const Axis chosen = axis_of(axis);
  const bool plain = profile_axis(chosen.motor) == nullptr;
  const std::string text = quantity_text(position, chosen, Dimension::kPosition, "position");
  Result<Quantity> quantity = parse_quantity(text);
  if (!quantity) invalid("position: " + quantity.error().message);
  Failure failure;
  std::vector<std::string> notes;
  const uint32_t m = chosen.motor;
  MotorStatus motor = call([&](Session& s) {
    Axis a = chosen;
    if (plain) a.microstep = s.model().motor(m).microstep;
    Result<StepCount> steps = a.to_steps(*quantity, Dimension::kPosition);
    if (!steps) {
      failure.usage = "position: " + steps.error().message;
      return s.model().motor(m);
    }
    if (steps->rounded()) notes.push_back("position " + text + " is " + number_text(steps->exact) + " steps: rounded to " + std::to_string(steps->steps));
    if (SessionResult<BoardFrame> done = s.execute(set_position_command(a, steps->exact / a.steps_per_unit())); !done) {
      failure.session = done.error();
      return s.model().motor(m);
    }
    if (std::optional<SoftLimits> limits = soft_limits_command(a); limits && !plain && s.firmware() == Firmware::kV2) {
      if (SessionResult<BoardFrame> sent = s.execute(*limits); !sent) failure.session = sent.error();
    }
    return s.model().motor(m);
  });
  warn_rounding(notes);
  failure.raise_if_any();
  return motor_record(motor, std::nullopt, profile_axis(m));
}

void Board::wait(const py::object& axis, std::optional<double> timeout_s) {
  const std::vector<uint32_t> motors = motors_of(axis);
  const std::optional<Millis> limit = limit_of(timeout_s);
  SessionResult<Done> done = call([&](Session& s) { return s.wait_until_idle(motors, limit); });
  if (!done) {
    for (uint32_t m : motors) started_.erase(m);  // a failed wait stopped every motor
    raise_session_error(done.error());
  }
  for (uint32_t m : motors) {
    if (started_.erase(m) == 0) continue;
    const std::optional<MotionEnd> end = session_->model().last_end[m - 1];
    if (end && *end != MotionEnd::kCompleted) {
      const MotorRecord record = motor_record(session_->model().motor(m), end, profile_axis(m));
      raise_ended_early(m, motion_end_name(*end), record,
                        "motor " + std::to_string(m) + "'s move ended early: " + motion_end_name(*end) + ", at " +
                            std::to_string(record.position) + " steps");
    }
  }
}

// ---- servos, strips, status, frames -------------------------------------------------------

void Board::servo(uint32_t servo, double angle) {
  if (!std::isfinite(angle)) invalid("angle must be a number of degrees, 10-170");
  const ServoMove move{servo, static_cast<uint32_t>(std::max(0.0, std::round(angle)))};
  SessionResult<BoardFrame> done = call([&](Session& s) { return s.execute(move); });
  if (!done) raise_session_error(done.error());
}

void Board::led(uint32_t strip, const py::object& colour) {
  LedColor command{strip, 0, 0, 0, 0};
  if (py::isinstance<py::str>(colour)) {
    Result<LedColor> parsed = parse_led_colour(strip, colour.cast<std::string>());
    if (!parsed) invalid(parsed.error().message);
    command = *parsed;
  } else if (py::isinstance<py::tuple>(colour) || py::isinstance<py::list>(colour)) {
    const std::vector<long> parts = colour.cast<std::vector<long>>();
    if (parts.size() != 3 && parts.size() != 4) invalid("a colour tuple is (r, g, b) or (r, g, b, w), each 0-255");
    for (long p : parts) {
      if (p < 0 || p > 255) invalid("colour values are 0-255, not " + std::to_string(p));
    }
    command = LedColor{strip, static_cast<uint32_t>(parts[0]), static_cast<uint32_t>(parts[1]), static_cast<uint32_t>(parts[2]),
                       parts.size() == 4 ? static_cast<uint32_t>(parts[3]) : 0u};
  } else {
    raise(PyExc_TypeError, "colour is '#RRGGBB', '#RRGGBBWW', 'off' or a tuple (r, g, b[, w])");
  }
  SessionResult<BoardFrame> done = call([&](Session& s) { return s.execute(command); });
  if (!done) raise_session_error(done.error());
}

StatusRecord Board::status() {
  const Profile* profile = profile_ ? &*profile_ : nullptr;
  Failure failure;
  StatusRecord record = call([&](Session& s) {
    if (SessionResult<Done> fresh = s.refresh(); !fresh) failure.session = fresh.error();
    return status_record(s, profile);
  });
  failure.raise_if_any();
  return record;
}

FrameRecord Board::send(const std::string& text, bool raw) {
  std::optional<Diagnostic> bad;
  SessionResult<BoardFrame> reply = call([&](Session& s) -> SessionResult<BoardFrame> {
    if (raw) return s.send_line(text);
    Result<Command, Diagnostic> command = command_from_text(text);
    if (!command) {
      bad = command.error();
      return BoardFrame{Ack{}};
    }
    return s.execute(*command);
  });
  if (bad) raise_diagnostic(*bad, text);
  if (!reply) raise_session_error(reply.error());
  return board_frame_record(*reply, proto::ChecksumMode::kSum);
}

void Board::arm_watchdog(double timeout_s) {
  if (!(timeout_s > 0) || timeout_s * 1000 > proto::kWatchdogMaxMs) {
    invalid("the watchdog's timeout is above 0 and at most " + std::to_string(proto::kWatchdogMaxMs / 1000) + " s");
  }
  SessionResult<Done> done = call([&](Session& s) -> SessionResult<Done> {
    if (SessionResult<Done> able = s.require(proto::Feature::kLinkWatchdog); !able) return able;
    return s.arm_watchdog(millis(timeout_s));
  });
  if (!done) raise_session_error(done.error());
}

void Board::disarm_watchdog() {
  SessionResult<Done> done = call([&](Session& s) -> SessionResult<Done> {
    if (!s.watchdog_armed()) return Done{};
    return s.disarm_watchdog();
  });
  if (!done) raise_session_error(done.error());
}

std::string Board::description() const { return session_ ? session_->description() : "closed"; }

std::string Board::firmware() const {
  if (!session_ || session_->firmware() == Firmware::kSeed) return "seed";
  return session_->version() ? firmware_version_text(session_->version()->firmware) : "unknown";
}

std::optional<uint32_t> Board::protocol() const {
  if (!session_ || !session_->version()) return std::nullopt;
  return session_->version()->protocol;
}

std::pair<uint32_t, uint32_t> Board::step_budgets() {
  SessionResult<StepBudgets> got = call([](Session& s) { return s.step_budgets(); });
  if (!got) raise_session_error(got.error());
  return {got.value().constant, got.value().ramping};
}

bool Board::simulated() const { return session_ && session_->simulated(); }
bool Board::watchdog_armed() const { return session_ && session_->watchdog_armed(); }

py::object Board::profile_axes() const {
  py::list names;
  if (profile_) {
    for (const Axis& a : profile_->axes) names.append(a.name);
  }
  return std::move(names);
}

// ---- motion files -------------------------------------------------------------------------

size_t Board::run_file(const std::string& path, py::object progress, size_t start_at, const StartPositions& at) {
  if (start_at < 1) invalid("start_at counts from 1");
  motion::ReadOptions read;
  if (profile_) {
    // A file that names no profile and declares no motors is in the board's; one that names
    // another profile is refused (the profile was chosen, not a default).
    read.profile = &*profile_;
    read.profile_chosen_by = "profile=";
  }
  Result<motion::MotionFile, std::vector<motion::FileError>> file = motion::load_motion_file(path, read);
  Failure failure;
  std::optional<motion::RunReport> report;
  size_t actions = 0;
  if (!file) failure.file_errors = file.error();
  if (file) warn_rounding(file->notes);
  if (!failure.file_errors) {
    call([&](Session& s) -> int {
      motion::PlanOptions options;
      options.firmware = s.firmware() == Firmware::kV2 ? motion::TargetFirmware::kV2 : motion::TargetFirmware::kSeed;
      options.budgets = s.step_budgets_in_force();
      if (at) {
        // Resuming: the plan counts from where the motors were when the file first started.
        for (uint32_t m = 1; m <= proto::kMotorCount; ++m) options.start_position[m - 1] = (*at)[m - 1];
      } else {
        // Absolute moves start from where the board says each motor is.
        motion::start_where_board_is(s, *file, options);
      }
      auto plan = motion::plan_motion(*file, options);
      if (!plan) {
        failure.file_errors = plan.error();
        return 0;
      }
      actions = plan->actions.size();
      if (start_at > actions) {
        failure.usage = "start_at=" + std::to_string(start_at) + ": the plan has only " + std::to_string(actions) + " steps";
        return 0;
      }
      motion::RunOptions run_options;
      run_options.from = start_at;
      run_options.resume = at.has_value();
      if (!progress.is_none()) {
        run_options.on_event = [this, &progress](const motion::RunEvent& e) {
          if (!python_polls_) return;
          ProgressRecord r;
          r.kind = e.kind == motion::RunEvent::Kind::kActionStarted ? "started"
                   : e.kind == motion::RunEvent::Kind::kActionDone  ? "done"
                                                                     : "returning";
          r.step = e.action != nullptr ? e.action->index : 0;
          r.total = e.total;
          r.description = e.action != nullptr ? e.action->description : "returning to the plan";
          r.elapsed_s = e.elapsed_s;
          r.remaining_s = e.remaining_s;
          py::gil_scoped_acquire gil;
          try {
            progress(r);
          } catch (py::error_already_set& error) {
            if (!pending_) pending_ = error;
            pending_flag_ = true;
          }
        };
      }
      motion::MotionRunner runner(s, *plan);
      report = runner.run(run_options);
      return 0;
    });
  }
  if (failure.file_errors) raise_motion_file_error(*failure.file_errors);
  failure.raise_if_any();
  if (report && report->error) raise_session_error(*report->error);
  return report ? report->completed : 0;
}

}  // namespace hmc::python
