// MotionRunner: carries out a Plan (motion_plan.h) on a board through a Session, action by
// action, reporting progress; on Ctrl-C or a failure it stops every motor (braking where the
// board has an acceleration set) and reports where each stopped and which action was running,
// so `--from` can resume there.
//
// A move's stages run one after another per motor, each sent when the motor's previous stage has
// ended (our firmware: its end event; the seed's: the time it must take); stages of different
// motors run at once. A move that does not wait keeps being fed while later actions run.
#pragma once

#include <array>
#include <cstddef>
#include <deque>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "hmc/motion_plan.h"
#include "hmc/session.h"

namespace hmc::motion {

struct RunEvent {
  enum class Kind : uint8_t { kActionStarted, kActionDone, kReturning };
  Kind kind = Kind::kActionStarted;
  const Action* action = nullptr;
  size_t total = 0;          // actions in the plan
  double elapsed_s = 0;      // since the run began
  double remaining_s = 0;    // planned time left after this point
};

struct RunOptions {
  size_t from = 1;  // the action to start at (1-based); earlier ones are skipped
  // Resuming: move each motor first to where the plan has it when action `from` starts
  // (needs positions the board reports).
  bool return_to_plan = true;
  // Resuming from the first action too (`hmc run --at`): the motors go first to where the plan
  // starts, since an interrupted first action left them somewhere on the way.
  bool resume = false;
  std::function<void(const RunEvent&)> on_event;
};

struct RunReport {
  size_t completed = 0;        // actions carried out in full
  size_t stopped_at = 0;       // the action running when the run stopped (0: it finished)
  std::optional<SessionError> error;  // why it stopped early
};

// Where the plan has every motor (steps at its microstep) when action `index` starts: exactly where
// a run from the start would have it then, a start between two steps included.
std::array<std::optional<double>, proto::kMotorCount> planned_positions(const Plan& plan, size_t index);

// Where the board says each of the file's motors stands (steps at each motor's microstep, a fraction
// between two of them), as the start positions of a plan run from here. With our firmware; the
// seed's reports no positions, so nothing is set.
void start_where_board_is(const Session& session, const MotionFile& file, PlanOptions& options);

class MotionRunner {
 public:
  MotionRunner(Session& session, const Plan& plan);
  RunReport run(const RunOptions& options);

 private:
  SessionResult<Done> run_action(const Action& action);
  SessionResult<Done> start_stages(const std::vector<std::vector<Stage>>& stages);
  // Sends the next stage of every motor whose previous one has ended.
  SessionResult<Done> feed();
  SessionResult<Done> wait_motors(const std::vector<uint32_t>& motors);
  SessionResult<Done> wait_until(Clock::time_point when);
  SessionResult<Done> return_to(const std::array<std::optional<double>, proto::kMotorCount>& positions);
  void emit(RunEvent::Kind kind, const Action* action);

  Session& session_;
  const Plan& plan_;
  std::function<void(const RunEvent&)> on_event_;
  Clock::time_point started_;
  std::array<std::deque<Stage>, proto::kMotorCount> queued_;  // stages not yet sent, per motor
  std::optional<SessionError> feed_error_;
};

}  // namespace hmc::motion
