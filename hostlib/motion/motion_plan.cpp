// Motion planning (motion_plan.h): a validated motion file turned into actions, STM stages and
// every motor's velocity over time. The Planner here walks the file once, keeping time, positions
// and what is still moving; the parts it uses, each over the one below it:
//   coordinated_move.h  when each motor of a move starts, and coordinated motors ending together;
//   motor_move.h        one motor's move alone: its stages, the firmware's trapezoid, rate rules;
//   ramp_shapes.h       ideal velocity profiles and their cutting into stages.
// plan_plot.cpp draws the result.
#include "hmc/motion_plan.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <tuple>
#include <utility>

#include "coordinated_move.h"
#include "hmc/axis_moves.h"
#include "hmc/codec.h"
#include "motor_move.h"
#include "plan_check.h"
#include "ramp_shapes.h"

namespace hmc::motion {
namespace {

using namespace planning;

constexpr double kHomeEstimateS = 0.5;
constexpr double kFadeFrameS = 0.05;

std::string signed_steps(int64_t steps) { return (steps >= 0 ? "+" : "") + std::to_string(steps) + " steps"; }

std::string colour_words(const Colour& c) {
  return std::to_string(c.r) + "," + std::to_string(c.g) + "," + std::to_string(c.b) + "," + std::to_string(c.w);
}

bool has_location(const Location& l) { return l.line != 0 || !l.path.empty(); }

// ---------------------------------------------------------------------------------------
// The planner: walks the file once, keeping time, positions and what is still moving

// A step's place in its file: its line and column.
using Place = std::pair<uint32_t, uint32_t>;

class Planner {
 public:
  // With `broken`, the planner checks a file with mistakes (plan_check.h): the steps at those
  // locations are placeholders, and only mistakes of position are kept.
  Planner(const MotionFile& file, const PlanOptions& options, const std::set<Place>* broken = nullptr)
      : file_(file), options_(options), broken_(broken) {
    for (uint32_t m = 0; m < proto::kMotorCount; ++m) {
      // A motor between two whole steps: the plan counts from the nearest, and the motor stays
      // `offset` off every position the plan gives it, until it is homed.
      const double start = options.start_position[m].value_or(0);
      motors_[m].position = std::llround(start);
      motors_[m].exact = static_cast<double>(motors_[m].position);
      motors_[m].offset = start - static_cast<double>(motors_[m].position);
      motors_[m].known = options.start_position[m].has_value();
    }
  }

  Result<Plan, std::vector<FileError>> run() {
    if (broken_ != nullptr) {
      walk_positions(file_.steps);
      return errors_;
    }
    walk(file_.steps, "");
    check_budget();
    if (!errors_.empty()) {
      std::stable_sort(errors_.begin(), errors_.end(), [](const FileError& a, const FileError& b) {
        return a.where.line != b.where.line ? a.where.line < b.where.line : a.where.column < b.where.column;
      });
      return errors_;
    }
    plan_.duration_s = now_;
    for (const MotorState& ms : motors_) plan_.duration_s = std::max(plan_.duration_s, ms.busy_until);
    for (const MotorConfig& c : file_.motors) plan_.tracks.push_back(track(c));
    return std::move(plan_);
  }

 private:
  struct MotorState {
    int64_t position = 0;  // steps; when not known, counted from wherever the motor was
    double exact = 0;      // the position before rounding to a whole step: relative moves add to it
    double offset = 0;     // how far the motor stands off `position` (a fraction of a step), until homed
    bool known = false;
    bool lost = false;     // checking: a broken step came since the position was last set
    double busy_until = 0;
    // The last motion, while a stop may still cut it short.
    bool moving = false;
    size_t action = 0, slot = 0, first_point = 0, first_boundary = 0;
    double brake = 0;  // the acceleration it brakes at when stopped (0: stops at once)
    std::vector<VelocityPoint> velocity;
    std::vector<double> boundaries;
  };

  void error(const Location& where, std::string expected, std::string found, std::string message) {
    if (broken_ != nullptr) return;  // checking: only mistakes of position (plan_check.h)
    errors_.push_back(FileError{where, std::move(expected), std::move(found), std::move(message)});
  }
  // Checking reports a mistake once, not once for every time a repeat comes round to it.
  void position_error(const Location& where, std::string expected, std::string found, std::string message) {
    if (broken_ != nullptr && !reported_.insert({where.line, where.column, message}).second) return;
    errors_.push_back(FileError{where, std::move(expected), std::move(found), std::move(message)});
  }

  const MotorConfig* motor(const std::string& name, const Location& where) {
    for (const MotorConfig& c : file_.motors) {
      if (c.name == name) {
        if (c.motor >= 1 && c.motor <= proto::kMotorCount) return &c;
        break;
      }
    }
    error(where, "a motor named in \"motors\"", name, "there is no motor named " + name);
    return nullptr;
  }

  double all_rest() const {
    double t = now_;
    for (const MotorState& ms : motors_) t = std::max(t, ms.busy_until);
    return t;
  }

  // Every command the plan sends must be one the board accepts.
  void check(const Command& command, const Location& where) {
    const Result<Command, Diagnostic> v = validate(command);
    if (!v.ok()) error(where, "a command the board accepts", describe(command), v.error().message);
  }

  Action& begin(ActionKind kind, const Step& step, const std::string& words, const std::string& pass, double start) {
    Action a;
    a.kind = kind;
    a.index = plan_.actions.size() + 1;
    a.description = step.label.empty() ? words + pass : step.label;
    a.where = step.where;
    a.start_s = a.end_s = start;
    plan_.actions.push_back(std::move(a));
    return plan_.actions.back();
  }

  void walk(const std::vector<Step>& steps, const std::string& pass) {
    for (const Step& step : steps) {
      if (const auto* r = std::get_if<RepeatStep>(&step.action)) {
        for (uint32_t i = 1; i <= r->count; ++i) {
          const std::string mine = "repeat " + std::to_string(i) + " of " + std::to_string(r->count);
          walk(r->steps, pass.empty() ? " (" + mine + ")" : pass.substr(0, pass.size() - 1) + ", " + mine + ")");
        }
      } else if (const auto* h = std::get_if<HomeStep>(&step.action)) {
        home(step, *h, pass);
      } else if (const auto* m = std::get_if<MoveStep>(&step.action)) {
        moves(step, {&m->move}, false, m->wait, pass);
      } else if (const auto* t = std::get_if<TogetherStep>(&step.action)) {
        std::vector<const Move*> list;
        for (const Move& mv : t->moves) list.push_back(&mv);
        moves(step, list, true, true, pass);
      } else if (const auto* s = std::get_if<ServoStep>(&step.action)) {
        servo(step, *s, pass);
      } else if (const auto* l = std::get_if<LedStep>(&step.action)) {
        led(step, *l, pass);
      } else if (const auto* w = std::get_if<WaitStep>(&step.action)) {
        wait(step, *w, pass);
      } else if (const auto* st = std::get_if<StopStep>(&step.action)) {
        stop(step, *st, pass);
      }
    }
  }

  // How a motor homes: plainly, or a profile axis as `hmc home` homes it (axis_moves.h), except
  // that the file owns the board while it runs: what the profile leaves out is set to none (with
  // our firmware), so that where homing ends is known.
  HomingSetup homing_of(const MotorConfig& c) const {
    const StepperMove plain{c.motor, proto::kActionHome, c.microstep, 0, 0};
    if (!c.axis) return HomingSetup{{}, plain, 0};
    const bool seed = options_.firmware == TargetFirmware::kSeed;
    return homing_setup(*c.axis, plain, seed ? UnsetHoming::kKeep : UnsetHoming::kNone);
  }

  // Homing: every motor must rest first (seed rule [2]); one motor after another.
  void home(const Step& step, const HomeStep& h, const std::string& pass) {
    std::string words = "home";
    std::vector<const MotorConfig*> configs;
    for (const std::string& name : h.motors) {
      words += (words == "home" ? " " : ", ") + name;
      const MotorConfig* c = motor(name, step.where);
      if (c == nullptr) continue;
      if (!proto::motor_has_switches(c->motor)) {
        error(step.where, "a motor with limit switches (1 or 2)", name + " (motor " + std::to_string(c->motor) + ")",
              name + " is motor " + std::to_string(c->motor) + ", which has no limit switch to home against");
        continue;
      }
      configs.push_back(c);
    }
    Action& a = begin(ActionKind::kHome, step, words, pass, all_rest());
    a.estimated = true;
    for (const MotorConfig* c : configs) {
      const HomingSetup setup = homing_of(*c);
      if (options_.firmware == TargetFirmware::kSeed && !setup.settings.empty()) {
        error(step.where, "our firmware (its SET home settings)", "the seed firmware",
              "the homing settings of axis '" + c->name + "' (docs/config.md) need SET, which the seed firmware does not know");
      }
      for (const SetSetting& set : setup.settings) {
        check(set, step.where);
        a.setup.push_back(set);
      }
      check(setup.move, step.where);
      a.commands_at_s.push_back(a.end_s);
      a.commands.push_back(setup.move);
      a.motors.push_back(c->motor);
      a.homed_at.push_back(setup.homed_position.value_or(0));
      a.end_s += kHomeEstimateS;
      // The board enforces the profile's soft limits too, once the motor is homed (as `hmc home`).
      if (const std::optional<SoftLimits> limits = c->axis && options_.firmware == TargetFirmware::kV2
                                                       ? soft_limits_command(*c->axis)
                                                       : std::nullopt) {
        check(*limits, step.where);
        a.commands_at_s.push_back(a.end_s);
        a.commands.push_back(*limits);
      }
    }
    for (size_t i = 0; i < configs.size(); ++i) {
      MotorState& ms = motors_[configs[i]->motor - 1];
      ms.position = a.homed_at[i];
      ms.exact = static_cast<double>(ms.position);
      ms.offset = 0;
      ms.known = true;
      ms.lost = false;
      ms.busy_until = a.end_s;
      ms.moving = false;
    }
    now_ = a.end_s;
  }

  // Where a move ends (it.delta, it.exact_end), and the mistakes of position: a `to` while the
  // position is not known, a move longer than one STM, an end beyond a soft limit. False: the
  // move is left out.
  bool place(Item& it) {
    const Move& mv = *it.move;
    MotorState& ms = motors_[it.config->motor - 1];
    // Where it ends: a relative move from the exact end of the one before, so that roundings to
    // whole steps never add up beyond half a step.
    // A position: the whole step that brings the motor nearest it, counting its offset.
    const double exact = mv.exact.value_or(mv.distance);
    it.exact_end = mv.absolute ? exact - ms.offset : ms.exact + exact;
    const int64_t target = std::llround(it.exact_end);
    if (mv.absolute && !ms.known && ms.lost) {  // checking, after a broken step: it counts from here
      ms.position = target;
      ms.exact = it.exact_end;
      ms.known = true;
      ms.lost = false;
      return false;
    }
    if (mv.absolute && !ms.known) {
      position_error(
          it.where, "a known position (home first, or a relative move)", "an unknown position",
          "the position of " + mv.motor + " is not known here: home it first, or move it by a relative distance");
      return false;
    }
    it.delta = target - ms.position;
    if (static_cast<uint64_t>(std::llabs(it.delta)) > proto::kIntMax && !(ms.lost && mv.absolute)) {
      position_error(it.where, "at most " + std::to_string(proto::kIntMax) + " steps", std::to_string(it.delta),
                     mv.motor + "'s move is longer than one STM can count");
      return false;
    }
    if (ms.known && !ms.lost) {
      const int64_t end = ms.position + it.delta;
      const MotorConfig& c = *it.config;
      const auto e = static_cast<double>(end);
      if ((c.min_position && e < *c.min_position) || (c.max_position && e > *c.max_position)) {
        const bool low = c.min_position && e < *c.min_position;
        const double limit = low ? *c.min_position : *c.max_position;
        position_error(it.where, std::string(low ? "a position of at least " : "a position of at most ") + num(limit),
                       std::to_string(end),
                       mv.motor + " would end at " + std::to_string(end) + " steps, beyond its soft limit of " +
                           num(limit) + " steps");
      }
    }
    return true;
  }

  // Moves a placed move's motor to its end (the motion itself is planned by moves()).
  void arrive(const Item& it) {
    MotorState& ms = motors_[it.config->motor - 1];
    ms.position += it.delta;
    ms.exact = it.exact_end;
    if (it.move->absolute) ms.lost = false;
  }

  // Checking (plan_check.h): positions only, with no actions, times or frames, so that a file of
  // many unrolled steps is checked quickly. A stop may cut a move short, which only its timing
  // tells: positions are not followed after one.
  void walk_positions(const std::vector<Step>& steps) {
    for (const Step& step : steps) {
      if (broken_->count({step.where.line, step.where.column}) != 0) {
        for (MotorState& ms : motors_) ms.lost = true;
      } else if (const auto* r = std::get_if<RepeatStep>(&step.action)) {
        for (uint32_t i = 0; i < r->count; ++i) walk_positions(r->steps);
      } else if (const auto* h = std::get_if<HomeStep>(&step.action)) {
        for (const std::string& name : h->motors) {
          const MotorConfig* c = motor(name, step.where);
          if (c == nullptr || !proto::motor_has_switches(c->motor)) continue;
          MotorState& ms = motors_[c->motor - 1];
          ms.position = homing_of(*c).homed_position.value_or(0);
          ms.exact = static_cast<double>(ms.position);
          ms.offset = 0;
          ms.known = true;
          ms.lost = false;
        }
      } else if (const auto* st = std::get_if<StopStep>(&step.action)) {
        for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
          bool named = st->motors.empty();
          for (const std::string& name : st->motors) {
            const MotorConfig* c = motor(name, step.where);
            named = named || (c != nullptr && c->motor == m);
          }
          if (named) motors_[m - 1].lost = true;
        }
      } else {
        std::vector<const Move*> list;
        if (const auto* m = std::get_if<MoveStep>(&step.action)) list.push_back(&m->move);
        if (const auto* t = std::get_if<TogetherStep>(&step.action)) {
          for (const Move& mv : t->moves) list.push_back(&mv);
        }
        for (const Move* mv : list) {
          Item it;
          it.move = mv;
          it.where = has_location(mv->where) ? mv->where : step.where;
          it.config = motor(mv->motor, it.where);
          if (it.config != nullptr && place(it)) arrive(it);
        }
      }
    }
  }

  void moves(const Step& step, const std::vector<const Move*>& list, bool together, bool wait,
             const std::string& pass) {
    std::vector<Item> items;
    std::string words = together ? "together:" : "move";
    for (const Move* mv : list) {
      Item it;
      it.move = mv;
      it.where = has_location(mv->where) ? mv->where : step.where;
      it.config = motor(mv->motor, it.where);
      if (it.config == nullptr) continue;
      for (const Item& other : items) {
        if (other.config->motor == it.config->motor) {
          error(it.where, "each motor once in a coordinated move", mv->motor, mv->motor + " is moved twice at once");
        }
      }
      if (!place(it)) continue;
      const int64_t target = motors_[it.config->motor - 1].position + it.delta;
      const std::string what = it.move->absolute
                                   ? " to " + std::to_string(target) + " (" + signed_steps(it.delta) + ")"
                                   : " " + signed_steps(it.delta);
      words += (items.empty() ? " " : ", ") + mv->motor + what + " (" + profile_words(mv->profile) + ")";
      items.push_back(std::move(it));
    }
    if (!wait) words += ", without waiting";
    if (together) words += ", arriving together";

    double start = now_;
    for (const Item& it : items) start = std::max(start, motors_[it.config->motor - 1].busy_until);
    Action& a = begin(ActionKind::kMove, step, words, pass, start);
    a.wait_for_motors = wait;
    const size_t action_index = plan_.actions.size() - 1;

    for (Item& it : items) {
      a.motors.push_back(it.config->motor);
      if (it.delta == 0) continue;  // nothing to do: an STM of 0 steps would run until stopped
      const uint32_t dir = it.delta > 0 ? proto::kActionForward : proto::kActionReverse;
      const int64_t start_units = motors_[it.config->motor - 1].position * 256 / it.config->microstep;
      const LinkTiming link{options_.baud, options_.firmware, start_units};
      Result<MotorPlan, Problem> p =
          plan_motor(*it.move, *it.config, static_cast<uint64_t>(std::llabs(it.delta)), dir, link, 1.0, nullptr);
      if (!p.ok()) {
        error(it.where, p.error().expected, p.error().found, p.error().message);
        continue;
      }
      it.natural = it.plan = p.value();
      it.planned = true;
    }

    if (together) coordinator_.coordinate(items);
    std::vector<Command> setup;
    const std::vector<double> off = coordinator_.offsets(items, setup);

    a.setup = setup;
    for (const Command& c : setup) check(c, step.where);
    double last_end = start;
    for (size_t k = 0; k < items.size(); ++k) {
      Item& it = items[k];
      MotorState& ms = motors_[it.config->motor - 1];
      arrive(it);
      std::vector<Stage> stages;
      if (it.planned) {
        const double t0 = start + off[k];
        ms.first_point = ms.velocity.size();
        ms.first_boundary = ms.boundaries.size();
        const double sign = it.plan.dir == proto::kActionForward ? 1.0 : -1.0;
        double t = t0;
        ms.velocity.push_back({t0, 0});
        for (size_t i = 0; i < it.plan.pieces.size(); ++i) {
          const Piece& pc = it.plan.pieces[i];
          if (i > 0) t += it.plan.gap_s(i);  // the runner sends a stage once the one before has ended
          Stage s{it.plan.motor, it.plan.dir, it.plan.microstep, static_cast<uint32_t>(pc.steps), pc.delay_us, t, 0};
          check(it.plan.stm(i), it.where);
          if (it.plan.firmware_ramp) {
            const Ideal p = trapezoid(static_cast<double>(pc.steps), 1e6 / pc.delay_us, it.plan.accel);
            for (const Segment& sg : p.segments()) ms.velocity.push_back({t0 + sg.t0 + sg.dur, sign * sg.v(sg.dur)});
            s.end_s = t0 + it.plan.duration_s();
            ms.velocity.back() = {s.end_s, 0};
          } else {
            s.end_s = t + static_cast<double>(pc.steps) * pc.delay_us / 1e6;
            if (it.plan.pieces.size() > 1) ms.boundaries.push_back(t);
            ms.velocity.push_back({t, sign * 1e6 / pc.delay_us});
            ms.velocity.push_back({s.end_s, sign * 1e6 / pc.delay_us});
          }
          t = s.end_s;
          stages.push_back(s);
        }
        if (!it.plan.firmware_ramp) ms.velocity.push_back({t, 0});
        ms.busy_until = t;
        ms.moving = true;
        ms.action = action_index;
        ms.slot = a.stages.size();
        ms.brake = it.plan.firmware_ramp ? it.plan.accel : 0;
        last_end = std::max(last_end, t);
      }
      a.stages.push_back(std::move(stages));
    }
    a.end_s = wait ? last_end : start;
    now_ = a.end_s;
  }

  // The seed's firmware refuses servo and LED frames while a stepper runs (seed rule [5]).
  double accessory_start() const { return options_.firmware == TargetFirmware::kSeed ? all_rest() : now_; }

  void servo(const Step& step, const ServoStep& s, const std::string& pass) {
    Action& a = begin(ActionKind::kServo, step, "servo " + std::to_string(s.servo) + " to " + num(s.angle) + "°", pass,
                      accessory_start());
    a.wait_for_motors = false;
    const Command cmd = ServoMove{s.servo, static_cast<uint32_t>(std::max(0.0, std::round(s.angle)))};
    check(cmd, step.where);
    a.commands.push_back(cmd);
    a.commands_at_s.push_back(a.start_s);
    now_ = a.end_s;
  }

  // A fade: one LED frame every 50 ms at most, the first the starting colour, the last the target.
  void led(const Step& step, const LedStep& l, const std::string& pass) {
    const size_t strip = std::clamp<uint32_t>(l.strip, 1, proto::kStripCount) - 1;
    const Colour from = l.from ? *l.from : strips_[strip];
    const bool fade = l.fade_ms > 0;
    std::string words = "LED strip " + std::to_string(l.strip);
    words +=
        fade ? " fade from " + colour_words(from) + " to " + colour_words(l.colour) + " in " + num(l.fade_ms) + " ms"
             : " to " + colour_words(l.colour);
    Action& a = begin(ActionKind::kLed, step, words, pass, accessory_start());
    a.wait_for_motors = false;
    const double fade_s = l.fade_ms / 1000.0;
    const size_t frames =
        fade ? std::max<size_t>(2, static_cast<size_t>(std::ceil(fade_s / kFadeFrameS - 1e-9)) + 1) : 1;
    for (size_t i = 0; i < frames; ++i) {
      const double f = frames == 1 ? 1.0 : static_cast<double>(i) / static_cast<double>(frames - 1);
      auto mix = [f](uint32_t x, uint32_t y) {
        return static_cast<uint32_t>(std::lround(x + (static_cast<double>(y) - x) * f));
      };
      const Command cmd = LedColor{l.strip, mix(from.r, l.colour.r), mix(from.g, l.colour.g), mix(from.b, l.colour.b),
                                   mix(from.w, l.colour.w)};
      check(cmd, step.where);
      a.commands.push_back(cmd);
      a.commands_at_s.push_back(a.start_s + fade_s * f);
    }
    a.end_s = a.start_s + (fade ? fade_s : 0);
    strips_[strip] = l.colour;
    now_ = a.end_s;
  }

  void wait(const Step& step, const WaitStep& w, const std::string& pass) {
    if (!w.until_done.empty()) {
      std::string words = "wait until";
      std::vector<uint32_t> numbers;
      double end = now_;
      for (const std::string& name : w.until_done) {
        words += (numbers.empty() ? " " : ", ") + name;
        if (const MotorConfig* c = motor(name, step.where)) {
          numbers.push_back(c->motor);
          end = std::max(end, motors_[c->motor - 1].busy_until);
        }
      }
      Action& a = begin(ActionKind::kWait, step, words + (numbers.size() > 1 ? " rest" : " rests"), pass, now_);
      a.motors = numbers;
      a.end_s = end;
    } else {
      Action& a = begin(ActionKind::kWait, step, "wait " + num(w.ms) + " ms", pass, now_);
      a.wait_for_motors = false;
      a.end_s = a.start_s + std::max(0.0, w.ms) / 1000.0;
    }
    now_ = plan_.actions.back().end_s;
  }

  // A stop cuts the motion of a motor still running: at once, or braking at its acceleration.
  void stop(const Step& step, const StopStep& s, const std::string& pass) {
    std::vector<uint32_t> numbers;
    std::string words = "stop";
    if (s.motors.empty()) {
      words += " all motors";
      for (uint32_t m = 1; m <= proto::kMotorCount; ++m) numbers.push_back(m);
    }
    for (const std::string& name : s.motors) {
      words += (numbers.empty() ? " " : ", ") + name;
      if (const MotorConfig* c = motor(name, step.where)) numbers.push_back(c->motor);
    }
    Action& a = begin(ActionKind::kStop, step, words, pass, now_);
    const size_t index = plan_.actions.size() - 1;
    double end = a.start_s;
    for (uint32_t m : numbers) {
      const Command cmd = StepperMove{m, proto::kActionStop, 0, 0, 0};
      check(cmd, step.where);
      plan_.actions[index].commands.push_back(cmd);
      plan_.actions[index].commands_at_s.push_back(plan_.actions[index].start_s);
      plan_.actions[index].motors.push_back(m);
      end = std::max(end, cut(m, plan_.actions[index].start_s));
    }
    plan_.actions[index].end_s = end;
    now_ = end;
  }

  // Cuts motor m's running motion at t; returns when it rests.
  double cut(uint32_t m, double t) {
    MotorState& ms = motors_[m - 1];
    if (!ms.moving || ms.busy_until <= t) return t;
    std::vector<VelocityPoint>& pts = ms.velocity;
    double v = 0;
    for (size_t i = ms.first_point; i + 1 < pts.size(); ++i) {
      if (pts[i].t_s <= t && t < pts[i + 1].t_s) {
        const double f = (t - pts[i].t_s) / (pts[i + 1].t_s - pts[i].t_s);
        v = pts[i].velocity + (pts[i + 1].velocity - pts[i].velocity) * f;
      }
    }
    size_t keep = ms.first_point;
    while (keep < pts.size() && pts[keep].t_s < t) ++keep;
    pts.resize(keep);
    pts.push_back({t, v});
    const double rest = ms.brake > 0 ? t + std::fabs(v) / ms.brake : t;
    pts.push_back({rest, 0});
    size_t kb = ms.first_boundary;
    while (kb < ms.boundaries.size() && ms.boundaries[kb] < t) ++kb;
    ms.boundaries.resize(kb);
    std::vector<Stage>& stages = plan_.actions[ms.action].stages[ms.slot];
    while (!stages.empty() && stages.back().start_s >= t) stages.pop_back();
    if (!stages.empty()) stages.back().end_s = rest;
    ms.busy_until = rest;
    ms.known = false;
    ms.moving = false;
    return rest;
  }

  // The board refuses a move whose rate takes the sum over moving motors beyond its budget:
  // checked when each stage starts, against the stage each other motor is running then.
  void check_budget() {
    struct Run {
      double start, end;
      uint32_t rate;
      bool ramping;
      size_t action;
    };
    std::array<std::vector<Run>, proto::kMotorCount> runs;  // per motor, in time order
    for (size_t i = 0; i < plan_.actions.size(); ++i) {
      const Action& a = plan_.actions[i];
      for (const std::vector<Stage>& stages : a.stages) {
        for (const Stage& s : stages) {
          bool ramping = false;
          for (const Command& c : a.setup) {
            const auto* set = std::get_if<SetSetting>(&c);
            if (set && set->motor == s.motor && set->setting == proto::kSettingAccel && set->value > 0) ramping = true;
          }
          runs[s.motor - 1].push_back({s.start_s, s.end_s, board_rate(std::max(1u, s.delay_us)), ramping, i});
        }
      }
    }
    std::vector<size_t> reported;
    for (uint32_t m = 0; m < proto::kMotorCount; ++m) {
      for (const Run& r : runs[m]) {
        uint32_t sum = r.rate;
        bool ramping = r.ramping;
        for (uint32_t o = 0; o < proto::kMotorCount; ++o) {
          if (o == m) continue;
          // The other motor's last stage starting by then, if it still runs.
          auto after = std::upper_bound(runs[o].begin(), runs[o].end(), r.start + 1e-12,
                                        [](double t, const Run& x) { return t < x.start; });
          if (after == runs[o].begin() || std::prev(after)->end <= r.start + 1e-9) continue;
          sum += std::prev(after)->rate;
          ramping = ramping || std::prev(after)->ramping;
        }
        const uint32_t limit = options_.budgets.when(ramping);
        if (sum <= limit || std::find(reported.begin(), reported.end(), r.action) != reported.end()) continue;
        reported.push_back(r.action);
        error(plan_.actions[r.action].where, "at most " + std::to_string(limit) + " steps/s in all",
              std::to_string(sum) + " steps/s",
              "the motors moving at once would step " + std::to_string(sum) +
                  " times a second in all; the board allows " + std::to_string(limit) +
                  (ramping ? " while any of them ramps" : ""));
      }
    }
  }

  MotorTrack track(const MotorConfig& c) const {
    const MotorState& ms = motors_[c.motor - 1];
    MotorTrack t;
    t.name = c.name;
    t.motor = c.motor;
    t.microstep = c.microstep;
    const std::optional<double>& start = options_.start_position[c.motor - 1];
    t.start_known = start.has_value();
    t.start_position = std::llround(start.value_or(0));
    t.start_exact = start.value_or(0);
    t.end_known = ms.known;
    t.end_position = ms.position;
    auto add = [&t](VelocityPoint p) {
      if (!t.velocity.empty() && t.velocity.back().t_s == p.t_s && t.velocity.back().velocity == p.velocity) return;
      t.velocity.push_back(p);
    };
    if (ms.velocity.empty() || ms.velocity.front().t_s > 0) add({0, 0});
    for (const VelocityPoint& p : ms.velocity) add(p);
    if (t.velocity.back().t_s < plan_.duration_s) add({plan_.duration_s, 0});
    t.stage_boundaries_s = ms.boundaries;
    return t;
  }

  const MotionFile& file_;
  const PlanOptions& options_;
  std::array<MotorState, proto::kMotorCount> motors_;
  std::array<Colour, proto::kStripCount> strips_{};  // black at the start of the file
  double now_ = 0;
  const std::set<Place>* broken_;
  std::set<std::tuple<uint32_t, uint32_t, std::string>> reported_;
  std::vector<FileError> errors_;
  Coordinator coordinator_{options_, errors_};
  Plan plan_;
};

}  // namespace

Result<Plan, std::vector<FileError>> plan_motion(const MotionFile& file, const PlanOptions& options) {
  return Planner(file, options).run();
}

std::vector<FileError> planning::position_mistakes(const MotionFile& partial, const std::vector<Location>& broken) {
  const PlanOptions options;  // as a check plans: no start positions known
  std::set<Place> places;
  for (const Location& b : broken) places.insert({b.line, b.column});
  auto result = Planner(partial, options, &places).run();
  return result.ok() ? std::vector<FileError>{} : result.error();
}

}  // namespace hmc::motion
