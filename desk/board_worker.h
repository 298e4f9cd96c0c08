// BoardWorker: the board's session on its own thread, so the panel never waits on the line.
//
// The panel posts requests (connect, jog, run, stop, servo, LED, motion file ...) into a queue
// and, once a frame, copies a Snapshot: the board model, the firmware, the connection state, the
// event log and a motion file's progress. Between requests the worker listens for the board's
// events and re-reads its state every 200 ms. STOP ALL does not queue: it raises a flag that
// every wait of the session polls (SessionOptions.interrupted), so a running motion file or any
// wait stops every motor at once, and the requests still queued are dropped.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "hmc/motion_plan.h"
#include "hmc/profile.h"
#include "hmc/session.h"

namespace hmc::desk {

enum class LinkState : uint8_t { kDisconnected, kConnecting, kConnected, kFailed };

struct LogLine {
  enum class Kind : uint8_t { kInfo, kSent, kReply, kEvent, kError };
  Kind kind = Kind::kInfo;
  double t_s = 0;  // since the worker started
  std::string text;
};

// A motion file opened and planned for the board connected (or for protocol v2 when none is).
struct LoadedFile {
  std::string path;
  std::vector<std::string> errors;  // "FILE:LINE:COLUMN: ..." each; empty when it planned
  std::shared_ptr<const motion::Plan> plan;
};

struct Snapshot {
  LinkState link = LinkState::kDisconnected;
  std::string port;
  std::string description;  // the session's description of the board
  std::optional<Firmware> firmware;
  std::string firmware_version;  // "1.0.0, protocol 2", "seed (no replies)"
  BoardModel model;
  bool busy = false;             // a request is being carried out, or queued
  std::vector<LogLine> log;      // the newest kLogLimit lines, oldest first
  uint64_t log_serial = 0;       // lines ever logged: the panel scrolls when it grows
  // Motion file
  LoadedFile file;
  bool running = false;
  size_t run_done = 0, run_total = 0;
  std::string run_action;
  double run_elapsed_s = 0, run_remaining_s = 0;
};

struct Request {
  enum class Kind : uint8_t {
    kConnect, kDisconnect, kMove, kRun, kHome, kStop, kServo, kLed, kOpenFile, kRunFile,
    kJog,       // a jog key: `dir` one jog step (kJogProfileSteps/kJogMotorSteps[level]) of the axis
    kGoTo,      // to the absolute position `text` ("250mm", "-90deg", "250": the axis's unit)
    kZero,      // set zero here (protocol 6)
    kStickRun,  // the gamepad: run at `rate` (`reverse`), up to the soft limit where it applies
  };
  explicit Request(Kind k, std::string t = {}) : kind(k), text(std::move(t)) {}
  Kind kind;
  std::string text;      // connect: the port; open/run file: the path
  uint32_t baud = 115200;
  uint32_t unit = 1;     // motor, servo or strip
  int64_t steps = 0;     // move: signed steps at the motor's microstep
  bool reverse = false;  // run
  uint32_t rate = 1000;  // steps/s
  uint32_t accel = 0;    // steps/s², 0: constant rate (v2 only)
  uint32_t angle = 90;
  uint32_t r = 0, g = 0, b = 0, w = 0;
  int dir = 1;           // jog: +1 or -1, in the axis's sense
  bool fast = false;     // jog: Shift held
  size_t level = 1;      // jog: the step size's index
  int count = 1;         // jog: how many such steps (a held key's repeats, added up in the queue)
};

class BoardWorker {
 public:
  static constexpr size_t kLogLimit = 400;

  // `profile` (may be null; it must outlive the worker) names the axes and gives their units.
  explicit BoardWorker(const Profile* profile = nullptr);
  ~BoardWorker();
  BoardWorker(const BoardWorker&) = delete;
  BoardWorker& operator=(const BoardWorker&) = delete;

  void post(Request request);
  // Preempts everything: interrupts the wait in progress (a running file included), drops the
  // queued requests and stops every motor.
  void stop_all();
  // Ends a running motion file (its motors are stopped, like STOP ALL).
  void stop_run() { stop_all(); }
  Snapshot snapshot() const;
  // The panel, once a frame while the gamepad holds an axis running: without it for
  // kStickSilence (the panel hung, the window is being dragged) the worker stops those axes.
  void stick_heartbeat();
  static constexpr Millis kStickSilence{500};

  // The axis motor `m` drives: the profile's, or a bare motor counted in steps (plain_motor_axis
  // at `microstep`). `described` says which.
  static Axis axis_of(const Profile* profile, uint32_t m, uint32_t microstep, bool* described = nullptr);

 private:
  void loop();
  void handle(const Request& request);
  void connect(const Request& request);
  void disconnect(const std::string& why);
  void send(const Command& command, const std::string& what);
  void open_file(const std::string& path);
  void run_file();
  void jog(const Request& request);
  void go_to(const Request& request);
  void zero(uint32_t motor);
  void stick_run(const Request& request);
  // Brings motor `m` to `target` (axis units) as an absolute move; false when it was not sent.
  bool move_to(uint32_t m, double target, const Request& request);
  // Sets motor m's acceleration when it differs from the one sent last (v2 only).
  bool set_accel(uint32_t m, uint32_t accel);
  // Stops motor m if it moves; false when the stop failed (reported).
  bool stop_if_moving(uint32_t m);
  // Reports a session error: a link failure ends the connection.
  void report(const SessionError& error, const std::string& what);
  void log(LogLine::Kind kind, std::string text);
  void publish();  // copies the session's model into the snapshot

  mutable std::mutex mutex_;  // guards queue_, snap_
  std::condition_variable wake_;
  std::deque<Request> queue_;
  Snapshot snap_;
  std::atomic<bool> stop_requested_{false};
  std::atomic<bool> quit_{false};
  std::atomic<int64_t> stick_alive_ns_{0};  // steady clock, the panel's last heartbeat
  const Profile* profile_;

  // Worker thread only
  std::unique_ptr<Session> session_;
  std::optional<uint32_t> accel_sent_[proto::kMotorCount];
  std::optional<double> jog_target_[proto::kMotorCount];  // axis units: the end of the jog under way
  bool stick_running_[proto::kMotorCount] = {};           // started by the gamepad, not stopped yet
  bool quiet_ = false;  // a status refresh: its queries and replies are not logged
  Clock::time_point started_ = Clock::now();
  Clock::time_point last_refresh_ = Clock::now();
  std::thread thread_;  // last: starts after everything above exists
};

}  // namespace hmc::desk
