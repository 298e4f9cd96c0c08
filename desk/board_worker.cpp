// BoardWorker: the session's thread. Every call into libhmc happens here; the panel only posts
// requests and copies snapshots.
#include "board_worker.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <utility>

#include "hmc/axis_moves.h"
#include "hmc/jog.h"
#include "hmc/motion_file.h"
#include "hmc/motion_runner.h"
#include "hmc/transport.h"

namespace hmc::desk {
namespace {

constexpr Millis kListenSlice{50};     // how long the worker listens between requests
constexpr Millis kRefreshEvery{200};   // status re-read while connected
constexpr Millis kLinkWatchdog{500};   // the board brakes after this long without a line

std::string version_text(const Version& v) {
  return std::to_string(v.firmware / 10000) + "." + std::to_string(v.firmware / 100 % 100) + "." +
         std::to_string(v.firmware % 100) + ", protocol " + std::to_string(v.protocol) + (v.legacy ? ", legacy rules" : "");
}

uint32_t delay_of(uint32_t rate) {
  return static_cast<uint32_t>(std::max<long>(1, std::lround(1e6 / std::max<uint32_t>(rate, 1))));
}

}  // namespace

BoardWorker::BoardWorker(const Profile* profile) : profile_(profile), thread_([this] { loop(); }) {}

Axis BoardWorker::axis_of(const Profile* profile, uint32_t m, uint32_t microstep, bool* described) {
  const Axis* axis = profile != nullptr ? profile->axis_of_motor(m) : nullptr;
  if (described != nullptr) *described = axis != nullptr;
  return axis != nullptr ? *axis : plain_motor_axis(m, microstep);
}

void BoardWorker::stick_heartbeat() {
  stick_alive_ns_ = std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}

BoardWorker::~BoardWorker() {
  quit_ = true;
  stop_requested_ = true;  // ends a running file or a wait, stopping the motors
  wake_.notify_all();
  thread_.join();
}

void BoardWorker::post(Request request) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    // A held key repeats faster than a jog stops and starts again: jogs still waiting in the
    // queue are added up, so that letting go of the key leaves at most one jog to carry out.
    if (request.kind == Request::Kind::kJog && !queue_.empty()) {
      Request& last = queue_.back();
      if (last.kind == Request::Kind::kJog && last.unit == request.unit && last.dir == request.dir &&
          last.fast == request.fast && last.level == request.level) {
        ++last.count;
        return;
      }
    }
    queue_.push_back(std::move(request));
    snap_.busy = true;
  }
  wake_.notify_all();
}

void BoardWorker::stop_all() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    // What was queued behind the stop would start motors again: only link changes survive.
    std::deque<Request> kept;
    for (Request& r : queue_) {
      if (r.kind == Request::Kind::kConnect || r.kind == Request::Kind::kDisconnect) kept.push_back(std::move(r));
    }
    queue_ = std::move(kept);
  }
  stop_requested_ = true;
  wake_.notify_all();
}

Snapshot BoardWorker::snapshot() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return snap_;
}

void BoardWorker::log(LogLine::Kind kind, std::string text) {
  const double t = std::chrono::duration<double>(Clock::now() - started_).count();
  std::lock_guard<std::mutex> lock(mutex_);
  snap_.log.push_back(LogLine{kind, t, std::move(text)});
  if (snap_.log.size() > kLogLimit) snap_.log.erase(snap_.log.begin());
  ++snap_.log_serial;
}

void BoardWorker::publish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (session_) snap_.model = session_->model();
  snap_.busy = !queue_.empty();
}

void BoardWorker::loop() {
  while (!quit_) {
    if (stop_requested_.exchange(false) && session_) {
      // The wait that saw the flag has stopped every motor already; once more costs three
      // short frames and covers a flag raised between waits.
      for (auto& target : jog_target_) target.reset();
      for (bool& running : stick_running_) running = false;
      if (SessionResult<Done> stopped = session_->stop_all(); !stopped) {
        report(stopped.error(), "stop all");
      } else {
        log(LogLine::Kind::kInfo, "STOP ALL: every motor was sent a stop");
      }
      publish();
    }
    // The gamepad's runs last only while the panel says so: a lost release is a motor running.
    const Clock::time_point alive{std::chrono::duration_cast<Clock::duration>(std::chrono::nanoseconds(stick_alive_ns_.load()))};
    for (uint32_t m = 1; m <= proto::kMotorCount && session_; ++m) {
      if (!stick_running_[m - 1] || Clock::now() - alive < kStickSilence) continue;
      stick_running_[m - 1] = false;
      log(LogLine::Kind::kError, "gamepad: no word from the panel for " + std::to_string(kStickSilence.count()) +
                                     " ms: motor " + std::to_string(m) + " stopped");
      send(StepperMove{m, proto::kActionStop, 0, 0, 0}, "motor " + std::to_string(m) + ": stop");
      publish();
    }
    std::optional<Request> request;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      if (queue_.empty() && !session_) wake_.wait_for(lock, kListenSlice);
      if (!queue_.empty()) {
        request = std::move(queue_.front());
        queue_.pop_front();
        snap_.busy = true;
      }
    }
    if (quit_) break;
    if (request) {
      handle(*request);
      publish();
      continue;
    }
    if (!session_) continue;
    if (SessionResult<Done> heard = session_->listen(kListenSlice); !heard) {
      report(heard.error(), "listening");
      continue;
    }
    if (session_ && Clock::now() - last_refresh_ >= kRefreshEvery) {
      last_refresh_ = Clock::now();
      quiet_ = true;  // the status queries are not worth a log line each
      SessionResult<Done> refreshed = session_->refresh();
      quiet_ = false;
      if (!refreshed) report(refreshed.error(), "reading the status");
    }
    publish();
  }
  if (session_) {
    (void)session_->stop_all();
    session_.reset();
  }
}

void BoardWorker::handle(const Request& q) {
  using K = Request::Kind;
  if (q.kind == K::kConnect) return connect(q);
  if (q.kind == K::kDisconnect) return disconnect("disconnected");
  if (q.kind == K::kOpenFile) return open_file(q.text);
  if (!session_) {
    log(LogLine::Kind::kError, "not connected: connect to a board first");
    return;
  }
  const uint32_t m = std::clamp<uint32_t>(q.unit, 1, proto::kMotorCount);
  const uint32_t microstep = session_->model().motor(m).microstep;
  const auto set_accel_q = [&] { return set_accel(m, q.accel); };
  switch (q.kind) {
    case K::kMove: {
      if (q.steps == 0 || !set_accel_q()) return;
      const uint32_t dir = q.steps < 0 ? proto::kActionReverse : proto::kActionForward;
      const auto steps = static_cast<uint32_t>(std::min<int64_t>(std::llabs(q.steps), 2147483647));
      send(StepperMove{m, dir, microstep, steps, delay_of(q.rate)},
           "motor " + std::to_string(m) + ": move " + std::to_string(q.steps) + " steps at " + std::to_string(q.rate) +
               " steps/s");
      return;
    }
    case K::kRun:
      if (!set_accel_q()) return;
      send(StepperMove{m, q.reverse ? proto::kActionReverse : proto::kActionForward, microstep, 0, delay_of(q.rate)},
           "motor " + std::to_string(m) + ": run " + (q.reverse ? "reverse" : "forward") + " until stopped");
      return;
    case K::kHome:
      send(StepperMove{m, proto::kActionHome, 0, 0, 0}, "motor " + std::to_string(m) + ": home");
      return;
    case K::kStop:
      jog_target_[m - 1].reset();
      stick_running_[m - 1] = false;
      send(StepperMove{m, proto::kActionStop, 0, 0, 0}, "motor " + std::to_string(m) + ": stop");
      return;
    case K::kServo:
      send(ServoMove{q.unit, q.angle}, "servo " + std::to_string(q.unit) + ": " + std::to_string(q.angle) + "°");
      return;
    case K::kLed:
      send(LedColor{q.unit, q.r, q.g, q.b, q.w}, "LED strip " + std::to_string(q.unit) + ": " + std::to_string(q.r) + " " +
                                                     std::to_string(q.g) + " " + std::to_string(q.b) + " " +
                                                     std::to_string(q.w));
      return;
    case K::kRunFile: run_file(); return;
    case K::kJog: jog(q); return;
    case K::kGoTo: go_to(q); return;
    case K::kZero: zero(m); return;
    case K::kStickRun: stick_run(q); return;
    default: return;
  }
}

void BoardWorker::connect(const Request& q) {
  if (session_) disconnect("disconnected");
  {
    std::lock_guard<std::mutex> lock(mutex_);
    snap_.link = LinkState::kConnecting;
    snap_.port = q.text;
  }
  log(LogLine::Kind::kInfo, "connecting to " + q.text + " at " + std::to_string(q.baud) + " baud");
  PortOptions port_options;
  port_options.baud = q.baud;
  Result<std::unique_ptr<Transport>> port = open_port(q.text, port_options);
  if (!port) {
    log(LogLine::Kind::kError, port.error().message);
    std::lock_guard<std::mutex> lock(mutex_);
    snap_.link = LinkState::kFailed;
    return;
  }
  SessionOptions options;
  options.interrupted = [this] { return stop_requested_.load(); };
  options.on_send = [this](std::string_view line) {
    if (!quiet_) log(LogLine::Kind::kSent, "> " + std::string(line));
  };
  options.on_line = [this](std::string_view line, const Result<BoardFrame, Diagnostic>& frame) {
    const bool event = frame && is_event(*frame);
    if (quiet_ && !event) return;
    log(event ? LogLine::Kind::kEvent : LogLine::Kind::kReply, "< " + std::string(line));
  };
  SessionResult<std::unique_ptr<Session>> session = Session::open(std::move(*port), options);
  stop_requested_ = false;  // a STOP ALL during the connection has nothing left to stop
  if (!session) {
    log(LogLine::Kind::kError, session.error().message);
    std::lock_guard<std::mutex> lock(mutex_);
    snap_.link = LinkState::kFailed;
    return;
  }
  session_ = std::move(*session);
  // A desk left running holds the board: should it die without a word, the board brakes.
  SessionResult<Done> watched = session_->simulated() ? SessionResult<Done>(Done{}) : session_->arm_watchdog(kLinkWatchdog);
  if (!watched) {
    log(LogLine::Kind::kInfo, "no link watchdog: " + watched.error().message);
  }
  for (auto& a : accel_sent_) a.reset();
  for (auto& target : jog_target_) target.reset();
  for (bool& running : stick_running_) running = false;
  last_refresh_ = Clock::now();
  log(LogLine::Kind::kInfo, "connected: " + session_->description());
  std::lock_guard<std::mutex> lock(mutex_);
  snap_.link = LinkState::kConnected;
  snap_.description = session_->description();
  snap_.firmware = session_->firmware();
  snap_.firmware_version = session_->version() ? version_text(*session_->version())
                                               : std::string("seed firmware (no replies; positions are timed)");
  snap_.model = session_->model();
}

void BoardWorker::disconnect(const std::string& why) {
  if (!session_) return;
  session_.reset();  // closes the port (a simulated board keeps its state)
  log(LogLine::Kind::kInfo, why);
  std::lock_guard<std::mutex> lock(mutex_);
  snap_.link = LinkState::kDisconnected;
  snap_.firmware.reset();
  snap_.firmware_version.clear();
  snap_.description.clear();
}

void BoardWorker::send(const Command& command, const std::string& what) {
  log(LogLine::Kind::kInfo, what);
  SessionResult<BoardFrame> reply = session_->execute(command);
  if (!reply) report(reply.error(), what);
}

void BoardWorker::report(const SessionError& error, const std::string& what) {
  using K = SessionError::Kind;
  const char* kind = error.kind == K::kNak        ? "the board refused"
                     : error.kind == K::kRefused  ? "refused"
                     : error.kind == K::kInvalid  ? "invalid"
                     : error.kind == K::kInterrupted ? "stopped"
                     : error.kind == K::kNoReply  ? "no reply"
                                                  : "link";
  log(error.kind == K::kInterrupted ? LogLine::Kind::kInfo : LogLine::Kind::kError,
      what + ": " + kind + ": " + error.message);
  if (error.kind == K::kLink || error.kind == K::kNoReply) {
    disconnect("connection lost");
    std::lock_guard<std::mutex> lock(mutex_);
    snap_.link = LinkState::kFailed;
  }
}

void BoardWorker::open_file(const std::string& path) {
  LoadedFile loaded;
  loaded.path = path;
  auto file = motion::load_motion_file(path);
  if (!file) {
    for (const motion::FileError& e : file.error()) loaded.errors.push_back(e.text());
  } else {
    motion::PlanOptions options;
    if (session_) {
      options.firmware = session_->firmware() == Firmware::kSeed ? motion::TargetFirmware::kSeed : motion::TargetFirmware::kV2;
      options.budgets = session_->step_budgets_in_force();
      // Absolute moves start from where the board says each motor is (its fraction of a step kept).
      motion::start_where_board_is(*session_, *file, options);
    }
    auto plan = motion::plan_motion(*file, options);
    if (!plan) {
      for (const motion::FileError& e : plan.error()) loaded.errors.push_back(e.text());
    } else {
      loaded.plan = std::make_shared<const motion::Plan>(std::move(*plan));
    }
  }
  log(loaded.errors.empty() ? LogLine::Kind::kInfo : LogLine::Kind::kError,
      path + (loaded.errors.empty() ? ": valid, " + std::to_string(loaded.plan->actions.size()) + " steps, " +
                                          std::to_string(loaded.plan->duration_s) + " s"
                                    : ": " + std::to_string(loaded.errors.size()) + " error(s)"));
  std::lock_guard<std::mutex> lock(mutex_);
  snap_.file = std::move(loaded);
}

void BoardWorker::run_file() {
  std::string path;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    path = snap_.file.path;
  }
  if (path.empty()) {
    log(LogLine::Kind::kError, "run: open a motion file first");
    return;
  }
  open_file(path);  // planned again from where the motors are now
  std::shared_ptr<const motion::Plan> plan;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    plan = snap_.file.plan;
    snap_.running = true;
    snap_.run_done = 0;
    snap_.run_total = plan ? plan->actions.size() : 0;
    snap_.run_action.clear();
  }
  if (!plan) {
    std::lock_guard<std::mutex> lock(mutex_);
    snap_.running = false;
    return;
  }
  log(LogLine::Kind::kInfo, "running " + path);
  motion::RunOptions options;
  options.on_event = [this](const motion::RunEvent& e) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (e.kind == motion::RunEvent::Kind::kActionDone && e.action) snap_.run_done = e.action->index;
      if (e.kind == motion::RunEvent::Kind::kActionStarted && e.action) snap_.run_action = e.action->description;
      snap_.run_elapsed_s = e.elapsed_s;
      snap_.run_remaining_s = e.remaining_s;
    }
    if (e.kind == motion::RunEvent::Kind::kActionStarted && e.action) {
      log(LogLine::Kind::kInfo, "step " + std::to_string(e.action->index) + "/" + std::to_string(e.total) + ": " +
                                    e.action->description);
    }
    publish();
  };
  motion::MotionRunner runner(*session_, *plan);
  const motion::RunReport outcome = runner.run(options);
  if (outcome.error) {
    report(*outcome.error, "run stopped at step " + std::to_string(outcome.stopped_at));
  } else {
    log(LogLine::Kind::kInfo, "run done: " + std::to_string(outcome.completed) + " steps");
  }
  std::lock_guard<std::mutex> lock(mutex_);
  snap_.running = false;
}

bool BoardWorker::set_accel(uint32_t m, uint32_t accel) {
  if (session_->firmware() != Firmware::kV2 || (accel_sent_[m - 1] && *accel_sent_[m - 1] == accel)) return true;
  SessionResult<BoardFrame> set = session_->execute(SetSetting{m, proto::kSettingAccel, accel});
  if (!set) {
    report(set.error(), "motor " + std::to_string(m) + " acceleration");
    return false;
  }
  accel_sent_[m - 1] = accel;
  return true;
}

bool BoardWorker::stop_if_moving(uint32_t m) {
  if (session_->model().motor(m).state == MotorState::kIdle) return true;
  if (SessionResult<Done> stopped = session_->stop({m}); !stopped) {
    report(stopped.error(), "motor " + std::to_string(m) + ": stop");
    return false;
  }
  return true;
}

bool BoardWorker::move_to(uint32_t m, double target, const Request& q) {
  bool described = false;
  const Axis axis = axis_of(profile_, m, session_->model().motor(m).microstep, &described);
  const std::string unit = unit_name(axis.unit());
  Result<UnitMove> planned = unit_move(axis, session_->model().motor(m),
                                       UnitMoveRequest{number_text(target, 6) + unit, std::nullopt, std::nullopt, std::nullopt});
  if (!planned) {
    log(LogLine::Kind::kError, axis.name + ": " + planned.error().message);
    return false;
  }
  for (const std::string& note : planned->notes) log(LogLine::Kind::kInfo, axis.name + ": note: " + note);
  if (!planned->move) return true;  // already there
  StepperMove move = *planned->move;
  // The profile's speed and acceleration when it gives them, else the motor panel's.
  move.delay_us = planned->delay_us ? *planned->delay_us : delay_of(q.rate);
  if (!set_accel(m, planned->accel ? *planned->accel : q.accel)) return false;
  const std::string steps = std::to_string(planned->target_position * axis.microstep / 256) + " steps";
  const std::string what = axis.name + ": to " + (described ? number_text(target) + " " + unit + " (" + steps + ")" : steps);
  log(LogLine::Kind::kInfo, what);
  SessionResult<BoardFrame> reply = session_->execute(move);
  if (!reply) {
    report(reply.error(), what);
    return false;
  }
  return true;
}

void BoardWorker::jog(const Request& q) {
  const uint32_t m = q.unit;
  bool described = false;
  const Axis axis = axis_of(profile_, m, session_->model().motor(m).microstep, &described);
  const MotorStatus& motor = session_->model().motor(m);
  const bool moving = motor.state != MotorState::kIdle;
  const size_t level = std::min(q.level, kJogProfileSteps.size() - 1);
  const double step = described ? kJogProfileSteps[level] : kJogMotorSteps[level] / axis.steps_per_unit();
  // A key while the jog still runs adds to where that jog ends, as `hmc jog` does.
  const double from = moving && jog_target_[m - 1] ? *jog_target_[m - 1] : axis.from_board_position(motor.position);
  const JogEnd end = jog_end(axis, motor, from, q.dir * q.count * step * (q.fast ? kJogShiftFactor : 1));
  if (end.at_limit) {
    log(LogLine::Kind::kInfo, axis.name + " stops at its soft limit " + number_text(end.target) + " " + unit_name(axis.unit()));
  }
  if (!stop_if_moving(m)) return;
  if (move_to(m, end.target, q)) jog_target_[m - 1] = end.target;
}

void BoardWorker::go_to(const Request& q) {
  const uint32_t m = q.unit;
  bool described = false;
  const Axis axis = axis_of(profile_, m, session_->model().motor(m).microstep, &described);
  // A bare number is in the axis's unit: mm or deg, steps on a motor no profile axis drives.
  std::string text = q.text;
  char* end = nullptr;
  std::strtod(text.c_str(), &end);
  if (!text.empty() && end != nullptr && *end == '\0') text += described ? unit_name(axis.unit()) : "steps";
  Result<Quantity> quantity = parse_quantity(text);
  if (!quantity) {
    log(LogLine::Kind::kError, axis.name + ": go to '" + q.text + "': " + quantity.error().message);
    return;
  }
  Result<StepCount> steps = axis.to_steps(*quantity, Dimension::kPosition);
  if (!steps) {
    log(LogLine::Kind::kError, axis.name + ": go to '" + q.text + "': " + steps.error().message);
    return;
  }
  const double target = steps->exact / axis.steps_per_unit();
  if (std::optional<std::string> beyond = beyond_soft_limits(axis, session_->model().motor(m), target)) {
    log(LogLine::Kind::kError, *beyond + ": not sent");
    return;
  }
  if (!stop_if_moving(m)) return;
  jog_target_[m - 1].reset();
  move_to(m, target, q);
}

void BoardWorker::zero(uint32_t m) {
  const Axis axis = axis_of(profile_, m, session_->model().motor(m).microstep);
  if (SessionResult<Done> able = session_->require(proto::Feature::kSetPosition); !able) {
    report(able.error(), axis.name + ": set zero");
    return;
  }
  if (session_->model().motor(m).state != MotorState::kIdle) {
    log(LogLine::Kind::kError, axis.name + " is moving: stop it before setting its zero");
    return;
  }
  jog_target_[m - 1].reset();
  send(set_position_command(axis, 0), axis.name + ": zero here");
  // Its position means something now: the profile's soft limits go to the board (as `hmc zero`).
  if (!session_ || session_->firmware() != Firmware::kV2) return;
  if (const std::optional<SoftLimits> limits = soft_limits_to_send(axis, session_->model().motor(m))) {
    send(*limits, axis.name + ": soft limits to the board");
  }
}

void BoardWorker::stick_run(const Request& q) {
  const uint32_t m = q.unit;
  if (!stop_if_moving(m) || !set_accel(m, q.accel)) return;
  const Axis axis = axis_of(profile_, m, session_->model().motor(m).microstep);
  const MotorStatus& motor = session_->model().motor(m);
  const double here = axis.from_board_position(motor.position);
  // Where the soft limits apply the run is a move to the limit ahead: it stops there by itself.
  const double far = 1e12;
  const JogEnd end = jog_end(axis, motor, here, q.reverse ? -far : far);
  jog_target_[m - 1].reset();
  StepperMove move;
  if (end.at_limit) {
    Result<UnitMove> planned =
        unit_move(axis, motor, UnitMoveRequest{number_text(end.target, 6) + unit_name(axis.unit()), std::nullopt, std::nullopt, std::nullopt});
    if (!planned || !planned->move) {
      log(LogLine::Kind::kInfo, axis.name + " is at its soft limit " + number_text(end.target) + " " + unit_name(axis.unit()));
      return;
    }
    move = *planned->move;
    log(LogLine::Kind::kInfo, axis.name + ": gamepad, " + std::to_string(q.rate) + " steps/s, up to its soft limit " +
                                  number_text(end.target) + " " + unit_name(axis.unit()));
  } else {
    // Positive is the axis's direction: the motor's reverse on an inverted axis.
    const bool forward = q.reverse == axis.invert;
    move = StepperMove{m, forward ? proto::kActionForward : proto::kActionReverse, axis.microstep, 0, 0};
    log(LogLine::Kind::kInfo, axis.name + ": gamepad, " + std::to_string(q.rate) + " steps/s " + (q.reverse ? "-" : "+") +
                                  " until let go");
  }
  move.delay_us = delay_of(q.rate);
  SessionResult<BoardFrame> reply = session_->execute(move);
  if (!reply) {
    report(reply.error(), axis.name + ": gamepad run");
    return;
  }
  stick_running_[m - 1] = true;
}

}  // namespace hmc::desk
