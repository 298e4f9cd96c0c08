// hmc.Board: one open board for Python, over a libhmc Session.
//
// Threads and the GIL: every call releases the GIL while it talks to the board, and takes one
// lock, so calls from several Python threads run one after another. While a call waits, the
// session's interruption callback takes the GIL every few tens of milliseconds, calls
// PyErr_CheckSignals() (Ctrl-C raises KeyboardInterrupt there) and runs the on_event callbacks
// for the events read so far — on the thread that made the call, never on another. A pending
// exception (KeyboardInterrupt, or one a callback raised) ends the wait: the session stops every
// motor, and the call raises that exception. Callbacks may not call the board: that is refused.
#pragma once

#include <pybind11/pybind11.h>

#include <array>
#include <atomic>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "hmc/axis_moves.h"
#include "hmc/profile.h"
#include "hmc/session.h"
#include "records.h"

namespace hmc::python {

struct OpenOptions {
  std::optional<std::string> port;
  std::optional<std::string> profile;
  std::optional<uint32_t> baud;
  double timeout_s = 1.0;
  std::string firmware = "auto";  // auto | v2 | seed
  double watchdog_s = 0.5;        // 0: none (never armed for sim://, whose board stops with us)
};

class Board {
 public:
  static std::unique_ptr<Board> open(const OpenOptions& options);
  ~Board();

  std::string description() const;
  std::string firmware() const;  // "0.1.0", or "seed"
  std::optional<uint32_t> protocol() const;
  // (constant, ramping) steps/s as VER reports them (protocol 7); FirmwareTooOld before.
  std::pair<uint32_t, uint32_t> step_budgets();
  bool simulated() const;
  bool watchdog_armed() const;
  py::object profile_axes() const;  // names of the profile's axes

  MotorRecord move(const py::object& axis, const py::object& to, const py::object& by, const py::object& steps,
                   const py::object& speed, const py::object& accel, bool wait, bool keep_running,
                   std::optional<double> timeout_s);
  void run(const py::object& axis, const py::object& rate, const py::object& accel, bool keep_running);
  void stop(const py::object& axis);
  void home(const py::object& axis);
  MotorRecord zero(const py::object& axis, const py::object& position);
  void wait(const py::object& axis, std::optional<double> timeout_s);
  void servo(uint32_t servo, double angle);
  void led(uint32_t strip, const py::object& colour);
  StatusRecord status();
  FrameRecord send(const std::string& command, bool raw);
  void arm_watchdog(double timeout_s);
  void disarm_watchdog();

  void on_event(py::object callback);
  // The next event, reading the board for at most `timeout_s` (None: until one comes); None when
  // none came in time.
  std::optional<EventRecord> next_event(std::optional<double> timeout_s);
  void listen(double seconds);

  // `at`: where motors 1-3 were (steps; None unknown) when the file first started: the motors go
  // first to where the plan has them at `start_at` (as `hmc run --from K --at P1,P2,P3`).
  using StartPositions = std::optional<std::array<std::optional<double>, proto::kMotorCount>>;
  size_t run_file(const std::string& path, py::object progress, size_t start_at, const StartPositions& at);

  // Stops the motors this board started (unless kept running), then closes the port.
  void close();
  bool closed() const { return session_ == nullptr; }

 private:
  Board() = default;
  // Runs `act` on the session without the GIL and under the board's lock; afterwards (GIL held)
  // runs callbacks and raises what a callback or Ctrl-C left pending.
  template <typename Act>
  auto call(Act&& act) -> decltype(act(std::declval<Session&>()));
  bool poll_python();  // the session's interruption callback
  void dispatch_events();  // with the GIL
  void raise_pending();    // with the GIL
  void on_line(std::string_view line, const Result<BoardFrame, Diagnostic>& frame);
  Axis axis_of(const py::object& axis) const;
  std::vector<uint32_t> motors_of(const py::object& axis) const;
  std::string quantity_text(const py::object& value, const Axis& axis, Dimension dimension, const char* name) const;
  const Axis* profile_axis(uint32_t motor) const;
  void stop_started(bool python_allowed);

  std::unique_ptr<Session> session_;
  std::optional<Profile> profile_;
  std::string port_;
  double watchdog_s_ = 0;

  std::mutex mutex_;                            // one call on the session at a time
  std::atomic<std::thread::id> caller_{};       // the thread inside a call
  std::atomic<bool> python_polls_{true};        // false while the destructor stops motors
  std::atomic<bool> pending_flag_{false};
  std::atomic<bool> has_callbacks_{false};
  Clock::time_point last_poll_{};
  std::optional<py::error_already_set> pending_;  // guarded by the GIL
  std::vector<py::object> callbacks_;             // guarded by the GIL
  bool dispatching_ = false;                      // guarded by the GIL: a callback runs

  std::mutex events_mutex_;           // events are read without the GIL
  std::deque<EventRecord> events_;    // for next_event(), at most kKeptEvents
  std::deque<EventRecord> undispatched_;  // for the callbacks
  std::set<uint32_t> started_;        // motors this board set moving that close() stops
};

}  // namespace hmc::python
