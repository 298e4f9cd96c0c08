// A grbl 1.1 front end over a Session: the board behind `hmc grbl`, as G-code senders (CNCjs,
// bCNC, Universal Gcode Sender) expect a grbl controller to behave (docs/grbl.md).
//
// The sender's bytes go in with receive(); what grbl would answer comes out of take_output().
// service() does the rest, a little at a time, so real-time bytes are answered while motors run:
// it reads the board's events, starts the next queued action when the last one ended, and
// answers complete lines — `ok` or `error:N` for each, grbl's numbers, an [MSG:…] line saying
// what was wrong; `ALARM:N` for a limit switch (1), a soft limit (2), the emergency switch or a
// stop during motion (3), homing that found no switch (9).
//
// Motion: every G0/G1 segment (and every chord of an arc) becomes one STM per moving motor, all
// sent back to back; each motor gets its share d_i/D of one speed and one acceleration, so the
// axes ramp, cruise and arrive together. Each segment starts and ends at rest (the board has no
// blending), and the next starts when every motor of the last one reported its end.
//
// The front end never leaves a motor running that nobody asked for: a soft reset (0x18), a
// sender that goes away (sender_gone) and every alarm stop every motor.
#pragma once

#include <array>
#include <chrono>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "hmc/gcode.h"
#include "hmc/profile.h"
#include "hmc/session.h"

namespace hmc::grbl {

inline constexpr const char* kBanner = "Grbl 1.1h ['$' for help]";
inline constexpr size_t kLineMax = 80;        // grbl's LINE_BUFFER_SIZE - 1: longer lines are error 11
inline constexpr size_t kRxBufferSize = 128;  // grbl's serial receive buffer, which senders count against
inline constexpr size_t kPlannerBlocks = 16;  // grbl's planner buffer: lines wait while it is full

// X, Y and Z: which axes of the profile they are (axes named x, y and z, in any case; without
// such names, the profile's axes in motor order), or without a profile motors 1, 2 and 3 as
// linear axes of 80 steps per mm (200 steps, 1/16, 40 mm per turn). An error when a named axis
// is rotary or the profile has no axis to map.
Result<std::array<std::optional<Axis>, kAxisCount>> map_axes(const Profile* profile);

// One of X, Y, Z as the front end drives it: its profile axis and grbl's per-axis settings.
struct GrblAxis {
  std::optional<Axis> axis;  // none: the letter has no axis here (error 20 when used)
  double max_rate = 0;       // $110: mm/min, what G0 uses
  double accel = 0;          // $120: mm/s^2; 0 constant rate
  double max_travel = 0;     // $130: mm
};

// grbl's machine states, as `?` names them.
enum class State : uint8_t { kIdle, kRun, kHold, kJog, kHome, kAlarm };
const char* state_name(State state);

class FrontEnd {
 public:
  FrontEnd(Session& session, const std::array<std::optional<Axis>, kAxisCount>& axes);

  // A sender connected: the banner (and, when the machine is locked, how to unlock it).
  void connected();
  // Bytes from the sender: real-time bytes act at the next service(); lines are queued.
  void receive(std::string_view bytes);
  // Reads the board and moves everything on; an error means the board is lost (every motor was
  // sent a stop if the link still carried it).
  SessionResult<Done> service();
  // The sender went away (closed the pseudo-terminal, dropped the connection): every motor stops,
  // queued lines and moves are dropped.
  SessionResult<Done> sender_gone();
  // Stops every motor and drops everything queued (Ctrl-C on `hmc grbl`).
  SessionResult<Done> stop();
  // What grbl would have sent since the last call.
  std::string take_output();

  State state() const { return state_; }
  const Interpreter& interpreter() const { return interpreter_; }

 private:
  struct Segment {
    std::array<int64_t, kAxisCount> target{};  // microsteps per axis, the axis's sense
    bool rapid = false;
    double feed = 0;  // mm/min
    bool jog = false;
  };
  struct Dwell {
    double seconds = 0;
  };
  struct BoardCommand {
    Command command;
  };
  struct Pause {};
  struct Home {};
  struct End {};
  using Action = std::variant<Segment, Dwell, BoardCommand, Pause, Home, End>;

  void line(const std::string& raw);
  void system_command(const std::string& clean);
  void gcode(const std::string& clean, bool jog);
  void setting(const std::string& clean);
  void send(const std::string& text) { out_ += text + "\r\n"; }
  void ok() { send("ok"); }
  void error(const GrblError& e);
  void message(const std::string& text) { send("[MSG:" + text + "]"); }

  SessionResult<Done> realtime();
  SessionResult<Done> advance();
  SessionResult<bool> start(Action& action);
  SessionResult<bool> finished(Action& action);
  SessionResult<Done> start_segment(const Segment& segment);
  SessionResult<Done> home_next();
  SessionResult<Done> alarm(int code, const std::string& why);
  SessionResult<Done> stop_moving();
  SessionResult<Done> status_report();
  SessionResult<Done> send_soft_limits();
  void drop_queue();
  void resync();
  void sync_ok();

  std::optional<std::string> beyond_limits(const Vec3& machine) const;
  int64_t microsteps(size_t axis) const;  // where the board says the axis is
  double machine_mm(size_t axis) const;
  std::vector<uint32_t> motors_of(const Segment& s) const;
  bool homing_enabled() const;
  std::string settings_text() const;
  std::string parameters_text() const;

  Session& session_;
  std::array<GrblAxis, kAxisCount> axes_;
  Interpreter interpreter_;
  State state_ = State::kIdle;
  bool hold_stopped_ = false;  // Hold:0 (at rest) rather than Hold:1 (stopping)
  std::string out_;
  std::string partial_;                 // a line not ended yet
  bool partial_overflow_ = false;
  bool last_was_cr_ = false;
  std::deque<std::string> lines_;       // ended lines waiting for the planner
  bool status_requested_ = false, hold_requested_ = false, resume_requested_ = false,
       reset_requested_ = false, jog_cancel_requested_ = false;
  std::vector<std::string> realtime_notes_;
  std::deque<Action> queue_;
  std::optional<Action> current_;
  bool current_started_ = false;
  std::vector<uint32_t> current_motors_;
  std::vector<size_t> homing_left_;          // axes $H still has to home
  Clock::time_point dwell_until_{};
  bool sync_pending_ = false;                // a line whose `ok` waits until the queue is empty
  std::array<std::optional<uint32_t>, proto::kMotorCount> accel_sent_{};
  bool emergency_seen_ = false;
  bool lost_sender_during_motion_ = false;
  // Settings that are the front end's own (the rest come from the axes).
  bool report_mpos_ = true;                  // $10 bit 0
  bool report_buffer_ = false;               // $10 bit 1
  bool report_inches_ = false;               // $13
  bool soft_limits_ = false;                 // $20
  bool homing_ = false;                      // $22
  size_t reports_ = 0;
  std::optional<Vec3> last_wco_;
};

}  // namespace hmc::grbl
