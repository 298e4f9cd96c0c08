// Internal to the motion module (planning): a move of several motors at once. It works out when
// each motor starts (the setup lines, then one STM per motor, each line on the wire and, with our
// firmware, answered), and for a coordinated (`together`) move slows every motor that would end
// early so that all end together, within one step period of each other (motor_move.h does the
// slowing of one motor).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "hmc/command.h"
#include "hmc/motion_file.h"
#include "hmc/motion_plan.h"
#include "motor_move.h"

namespace hmc::motion::planning {

// One motor of a move: its plan alone (natural) and as it will run (plan).
struct Item {
  const Move* move = nullptr;
  const MotorConfig* config = nullptr;
  Location where;
  int64_t delta = 0;
  double exact_end = 0;  // where it ends before rounding to a whole step
  MotorPlan natural, plan;
  bool planned = false;
};

class Coordinator {
 public:
  // Mistakes (a motor that cannot be slowed enough) go to `errors`.
  Coordinator(const PlanOptions& options, std::vector<FileError>& errors) : options_(options), errors_(errors) {}

  // Lines sent for a move: setup first, then the first STM of each motor. Start offsets per item.
  std::vector<double> offsets(const std::vector<Item>& items, std::vector<Command>& setup) const;
  // Coordinated: every motor ends when the last would (E = the latest start + own duration);
  // the others are slowed to end then too. A motor starts when its STM line has arrived, after
  // the setup lines and the STM lines before it, so each fit moves the starts of the motors
  // after it by the change in its line's length: a few rounds settle that, and a last round, if
  // needed, fits each motor keeping its lines' lengths so that no start moves any more.
  void coordinate(std::vector<Item>& items);

 private:
  // Makes one motor's move take `target_s` (>= its own duration): its profile slowed, else the
  // same ramp as stages, else one rate. Lengths (when not 0) are lines that must not change.
  bool fit_item(Item& it, double target_s, size_t stm_chars, size_t set_chars) const;
  // The last round of coordinating: the move's lines keep their length (the first STM stays as
  // it is, or our firmware's trapezoid keeps its lines' lengths), so no motor's start moves.
  bool refit_tail(Item& it, double target_s) const;
  void error(const Location& where, std::string expected, std::string found, std::string message) {
    errors_.push_back(FileError{where, std::move(expected), std::move(found), std::move(message)});
  }

  const PlanOptions& options_;
  std::vector<FileError>& errors_;
  double tolerance_s_ = kSyncToleranceS / 2;  // this coordinated move's (coordinate())
};

}  // namespace hmc::motion::planning
