// Motion files: the steps (StepChecker, motion_file_check.h) — home, move, together, servo, led,
// wait, repeat and stop, each checked against the format and the board's rules.
#include <cctype>
#include <cmath>
#include <iterator>
#include <set>
#include <string>
#include <utility>

#include "motion_file_check.h"

namespace hmc::motion::reading {

// Checks a list of steps into `out`; returns how many steps they unroll to.
uint64_t StepChecker::steps(const Value& list, const std::string& path, int repeat_depth, std::vector<Step>& out) {
  uint64_t total = 0;
  for (size_t i = 0; i < list.items.size(); ++i) {
    total += step(list.items[i], json::path_with_index(path, i), repeat_depth, out);
  }
  return total;
}

// One step; returns its unrolled size (0 when it yields no step).
uint64_t StepChecker::step(const Value& v, const std::string& path, int repeat_depth, std::vector<Step>& out) {
  const std::string shape = "a step: an object with one of " + Keys(kActions).list() + ", and an optional label";
  if (!v.is(Kind::kObject)) {
    r_.wrong_type(v, path, shape);
    return 0;
  }
  const size_t before = r_.count();
  const bool keys_ok = r_.known_keys(v, path, kStepKeys);
  const json::Member* action = nullptr;
  for (const json::Member& m : v.members) {
    if (!Keys(kActions).contains(m.key)) continue;
    if (action == nullptr) {
      action = &m;
    } else {
      r_.add(m.at, json::path_with_key(path, m.key), "one action per step", r_.found(m),
             "a step has one action: " + single_quoted(m.key) + " comes after " + single_quoted(action->key));
    }
  }
  if (action == nullptr) {
    if (keys_ok) r_.bad(v, path, "one of " + Keys(kActions).list(), "a step needs an action");
    return 0;
  }

  Step s;
  s.where = r_.location(v.at, path);
  if (const Value* label = r_.get(v, "label")) {
    if (auto text = r_.string(*label, json::path_with_key(path, "label"))) s.label = *text;
  }
  const Value& a = action->value;
  const std::string p = json::path_with_key(path, action->key);
  uint64_t size = 1;
  bool ok = false;
  if (action->key == "home") {
    ok = home(a, p, s);
  } else if (action->key == "move") {
    ok = move_step(a, p, s);
  } else if (action->key == "together") {
    ok = together(a, p, s);
  } else if (action->key == "servo") {
    ok = servo(a, p, s);
  } else if (action->key == "led") {
    ok = led(a, p, s);
  } else if (action->key == "wait") {
    ok = wait(a, p, s);
  } else if (action->key == "repeat") {
    size = repeat(a, p, repeat_depth, s);
    ok = size > 0;
  } else {  // stop
    ok = stop(a, p, s);
  }
  if (!ok || r_.count() != before || unconverted_) {
    // A broken step that may move motors leaves a placeholder (broken()); the others move none.
    if (action->key != "servo" && action->key != "led" && action->key != "wait") {
      Step placeholder;
      placeholder.where = s.where;
      placeholder.action = WaitStep{};
      out.push_back(std::move(placeholder));
      broken_.push_back(s.where);
    }
    unconverted_ = false;
    return 0;
  }
  out.push_back(std::move(s));
  return size;
}

bool StepChecker::home(const Value& v, const std::string& path, Step& s) {
  auto names = motors_.motor_names(v, path);
  if (!names) return false;
  bool ok = true;
  for (size_t i = 0; i < names->names.size(); ++i) {
    const MotorEntry* e = motors_.find_motor(names->names[i]);
    if (e == nullptr || e->config.motor == 0 || proto::motor_has_switches(e->config.motor)) continue;
    r_.bad(*names->nodes[i], path, "motors with limit switches (the board's motors 1 and 2)",
           single_quoted(names->names[i]) + " is the board's motor " + fmt(e->config.motor) +
               ", which has no limit switches to home against");
    ok = false;
  }
  s.action = HomeStep{std::move(names->names)};
  return ok;
}

bool StepChecker::stop(const Value& v, const std::string& path, Step& s) {
  auto names = motors_.motor_names(v, path);
  if (!names) return false;
  StopStep stop;
  if (!names->all) stop.motors = std::move(names->names);
  s.action = std::move(stop);
  return true;
}

bool StepChecker::move_step(const Value& v, const std::string& path, Step& s) {
  bool wait = true;
  auto m = move(v, path, false, wait);
  if (!m) return false;
  s.action = MoveStep{std::move(*m), wait};
  return true;
}

bool StepChecker::together(const Value& v, const std::string& path, Step& s) {
  if (!v.is(Kind::kArray) || v.items.size() < 2) {
    if (v.is(Kind::kArray)) {
      r_.bad(v, path, "a list of at least 2 moves", "a together step moves at least 2 motors");
    } else {
      r_.wrong_type(v, path, "a list of at least 2 moves");
    }
    return false;
  }
  const size_t before = r_.count();
  TogetherStep t;
  std::set<std::string> moving;
  for (size_t i = 0; i < v.items.size(); ++i) {
    const Value& item = v.items[i];
    const std::string p = json::path_with_index(path, i);
    bool unused = true;
    auto m = move(item, p, true, unused);
    if (!item.is(Kind::kObject)) continue;
    const Value* name = r_.get(item, "motor");
    if (name != nullptr && name->is(Kind::kString) && motors_.find_motor(name->string) != nullptr &&
        !moving.insert(name->string).second) {
      r_.bad(*name, json::path_with_key(p, "motor"), "each motor once in a together step",
             single_quoted(name->string) + " already moves in this step");
    }
    if (m) t.moves.push_back(std::move(*m));
  }
  if (r_.count() != before) return false;
  s.action = std::move(t);
  return true;
}

std::optional<Move> StepChecker::move(const Value& v, const std::string& path, bool in_together, bool& wait) {
  if (!v.is(Kind::kObject)) {
    r_.wrong_type(v, path, "a move: an object with motor and by or to");
    return std::nullopt;
  }
  const size_t before = r_.count();
  r_.known_keys(v, path, in_together ? Keys(kTogetherMoveKeys) : Keys(kMoveKeys));
  Move m;
  m.where = r_.location(v.at, path);

  const MotorEntry* e = nullptr;
  if (const Value* n = r_.get(v, "motor")) {
    e = motors_.motor_ref(*n, json::path_with_key(path, "motor"), false);
    if (n->is(Kind::kString)) m.motor = n->string;
  } else {
    r_.missing(v, path, "motor", "a motor name");
  }
  const Scale scale = e != nullptr ? e->scale() : Scale{};

  // Where to: exactly one of by and to.
  const json::Member* by = v.find("by");
  const json::Member* to = v.find("to");
  if (by != nullptr && to != nullptr) {
    const json::Member& later = by->at.offset > to->at.offset ? *by : *to;
    const json::Member& earlier = &later == by ? *to : *by;
    r_.add(later.at, json::path_with_key(path, later.key), "either 'by' or 'to'", r_.found(later),
           "a move has either 'by' (relative) or 'to' (absolute), not both: " + single_quoted(later.key) + " after " +
               single_quoted(earlier.key));
  } else if (by != nullptr) {
    const std::string p = json::path_with_key(path, "by");
    if (auto q = q_.quantity(by->value, p, Dim::kDistance, scale)) {
      const double steps = std::round(q->value) + 0.0;
      if (steps == 0) {
        r_.bad(*q->node, q->path, "a distance of at least one whole step",
               q_.described(*q, "steps") + " moves 0 steps");
      } else if (q_.steps_ok(*q, steps)) {
        m.distance = steps;
        if (std::fabs(q->value - steps) > kWholeStep) {
          m.exact = q->value;
          r_.note(*q->node, q->path,
                  q->written + " is " + fmt(q->value) +
                      " steps: the move ends at the whole step nearest its exact end, so roundings do not add up");
        }
      }
    } else {
      unconverted_ = true;
    }
  } else if (to != nullptr) {
    const std::string p = json::path_with_key(path, "to");
    m.absolute = true;
    if (auto q = q_.quantity(to->value, p, Dim::kDistance, scale)) {
      const double steps = std::round(q->value) + 0.0;  // + 0.0: no -0
      if (q_.steps_ok(*q, steps)) {
        m.distance = steps;
        if (std::fabs(q->value - steps) > kWholeStep) {
          m.exact = q->value;
          r_.note(*q->node, q->path, "position " + q->written + " is " + fmt(q->value) + " steps: rounded to " + fmt(steps));
        }
        const MotorConfig* c = e != nullptr ? &e->config : nullptr;
        const bool below = c != nullptr && c->min_position && steps < *c->min_position;
        const bool above = c != nullptr && c->max_position && steps > *c->max_position;
        if (below || above) {
          std::string range = "a position within " + shown(m.motor) + "'s limits: ";
          if (c->min_position && c->max_position) {
            range += "from " + fmt(*c->min_position) + " to " + fmt(*c->max_position) + " steps";
          } else if (c->min_position) {
            range += "at least " + fmt(*c->min_position) + " steps";
          } else {
            range += "at most " + fmt(*c->max_position) + " steps";
          }
          r_.bad(*q->node, q->path, range,
                 "position " + q_.described(*q, "steps") + " is " + (below ? "below" : "above") + " " + shown(m.motor) +
                     "'s " + (below ? "min" : "max") + " limit " + fmt(below ? *c->min_position : *c->max_position) +
                     " steps");
        }
      }
    } else {
      unconverted_ = true;
    }
  } else {
    r_.add(v.at, json::path_with_key(path, "by"), "'by' (a relative distance) or 'to' (a position)", "nothing",
           "a move needs 'by' or 'to'");
  }

  // The profile: the move's own speed and acceleration, else the motor's.
  Profile& prof = m.profile;
  prof.speed = e != nullptr ? e->config.speed : 0;
  prof.accel = e != nullptr ? e->config.accel : 0;
  if (const Value* n = r_.get(v, "speed")) {
    if (auto q = q_.quantity(*n, json::path_with_key(path, "speed"), Dim::kSpeed, scale); q && q_.speed_ok(*q)) {
      prof.speed = q->value;
    }
  }
  // Whether prof.accel is what the file means (not a default standing in for a broken value).
  bool accel_known = e != nullptr && e->accel_ok;
  if (const Value* n = r_.get(v, "accel")) {
    accel_known = false;
    if (auto q = q_.quantity(*n, json::path_with_key(path, "accel"), Dim::kAccel, scale); q && q_.accel_ok(*q)) {
      prof.accel = q->value;
      accel_known = true;
    }
  }
  const Value* profile = r_.get(v, "profile");
  bool kind_known = true;
  prof.kind = prof.accel > 0 ? ProfileKind::kTrapezoid : ProfileKind::kConstant;
  if (profile != nullptr) {
    const std::string p = json::path_with_key(path, "profile");
    const std::string expected = "one of " + Keys(kProfiles).list();
    kind_known = false;
    if (!profile->is(Kind::kString)) {
      r_.wrong_type(*profile, p, expected);
    } else {
      for (size_t i = 0; i < std::size(kProfiles); ++i) {
        if (profile->string == kProfiles[i]) {
          prof.kind = kProfileKinds[i];
          kind_known = true;
        }
      }
      if (!kind_known) {
        r_.bad(*profile, p, expected,
               "unknown profile " + single_quoted(profile->string) + suggestion(profile->string, kProfiles));
      } else if ((prof.kind == ProfileKind::kTrapezoid || prof.kind == ProfileKind::kSCurve) && prof.accel <= 0 &&
                 accel_known) {
        r_.bad(*profile, p, "an acceleration above 0, in the move's 'accel' or its motor's",
               "the " + profile->string + " profile needs an acceleration above 0");
      }
    }
  }
  if (const Value* n = r_.get(v, "stages")) {
    const std::string p = json::path_with_key(path, "stages");
    if (kind_known && prof.kind != ProfileKind::kStaged) {
      r_.bad(*n, p, "'stages' only with \"profile\": \"staged\"", "'stages' applies to the staged profile only");
    } else if (auto k = r_.integer(*n, p, "stages", kMinStages, kMaxStages)) {
      prof.stages = *k;
    }
  }
  if (const Value* n = r_.get(v, "jerk")) {
    const std::string p = json::path_with_key(path, "jerk");
    if (kind_known && prof.kind != ProfileKind::kSCurve) {
      r_.bad(*n, p, "'jerk' only with \"profile\": \"s-curve\"", "'jerk' applies to the s-curve profile only");
    } else if (auto q = q_.quantity(*n, p, Dim::kJerk, scale)) {
      if (q->value <= 0) {
        r_.bad(*q->node, q->path, "a jerk above 0", "jerk " + q_.described(*q, "steps/s³") + " is not above 0");
      } else {
        prof.jerk = q->value;
      }
    }
  } else if (prof.kind == ProfileKind::kSCurve) {
    prof.jerk = prof.accel * kJerkPerAccel;
  }
  if (const Value* n = r_.get(v, "wait")) {  // only reached for move steps: together refuses the key
    if (!n->is(Kind::kBool)) {
      r_.wrong_type(*n, json::path_with_key(path, "wait"), "true or false");
    } else {
      wait = n->boolean;
    }
  }
  if (r_.count() != before || e == nullptr) return std::nullopt;
  return m;
}

bool StepChecker::servo(const Value& v, const std::string& path, Step& s) {
  if (!v.is(Kind::kObject)) {
    r_.wrong_type(v, path, "an object with id and angle");
    return false;
  }
  const size_t before = r_.count();
  r_.known_keys(v, path, kServoKeys);
  ServoStep out;
  if (const Value* n = r_.get(v, "id")) {
    if (auto id = r_.integer(*n, json::path_with_key(path, "id"), "servo", 1, proto::kServoCount)) out.servo = *id;
  } else {
    r_.missing(v, path, "id", "servo 1 or 2");
  }
  if (const Value* n = r_.get(v, "angle")) {
    if (auto a =
            r_.number(*n, json::path_with_key(path, "angle"), "angle", kMinServoAngle, kMaxServoAngle, " degrees")) {
      out.angle = *a;
    }
  } else {
    r_.missing(v, path, "angle", "an angle in degrees");
  }
  if (r_.count() != before) return false;
  s.action = out;
  return true;
}

std::optional<Colour> StepChecker::colour(const Value& v, const std::string& path) {
  const std::string expected = "\"#RRGGBB\", \"#RRGGBBWW\", [r, g, b], [r, g, b, w] or \"off\"";
  if (v.is(Kind::kString)) {
    if (v.string == "off") return Colour{};
    const std::string& t = v.string;
    const bool shape =
        (t.size() == 7 || t.size() == 9) && t[0] == '#' &&
        std::all_of(t.begin() + 1, t.end(), [](char c) { return std::isxdigit(static_cast<unsigned char>(c)) != 0; });
    if (!shape) {
      r_.bad(v, path, expected, "a colour is \"#\" and 6 or 8 hex digits, or \"off\"");
      return std::nullopt;
    }
    const auto digit = [](char c) { return static_cast<uint32_t>(c <= '9' ? c - '0' : (c | 0x20) - 'a' + 10); };
    const auto byte = [&](size_t i) { return digit(t[i]) * 16 + digit(t[i + 1]); };
    return Colour{byte(1), byte(3), byte(5), t.size() == 9 ? byte(7) : 0};
  }
  if (v.is(Kind::kArray)) {
    if (v.items.size() != 3 && v.items.size() != 4) {
      r_.bad(v, path, expected, "a colour list has 3 or 4 values (r, g, b and optionally w)");
      return std::nullopt;
    }
    static constexpr const char* kChannels[] = {"red", "green", "blue", "white"};
    uint32_t c[4] = {0, 0, 0, 0};
    bool ok = true;
    for (size_t i = 0; i < v.items.size(); ++i) {
      if (auto x = r_.integer(v.items[i], json::path_with_index(path, i), kChannels[i], 0, 255)) {
        c[i] = *x;
      } else {
        ok = false;
      }
    }
    if (!ok) return std::nullopt;
    return Colour{c[0], c[1], c[2], c[3]};
  }
  r_.wrong_type(v, path, expected);
  return std::nullopt;
}

bool StepChecker::led(const Value& v, const std::string& path, Step& s) {
  if (!v.is(Kind::kObject)) {
    r_.wrong_type(v, path, "an object with strip and colour");
    return false;
  }
  const size_t before = r_.count();
  r_.known_keys(v, path, kLedKeys);
  LedStep out;
  if (const Value* n = r_.get(v, "strip")) {
    if (auto strip = r_.integer(*n, json::path_with_key(path, "strip"), "strip", 1, proto::kStripCount))
      out.strip = *strip;
  } else {
    r_.missing(v, path, "strip", "strip 1 or 2");
  }
  if (const Value* n = r_.get(v, "colour")) {
    if (auto c = colour(*n, json::path_with_key(path, "colour"))) out.colour = *c;
  } else {
    r_.missing(v, path, "colour", "a colour");
  }
  if (const Value* n = r_.get(v, "from")) {
    if (auto c = colour(*n, json::path_with_key(path, "from"))) out.from = *c;
  }
  if (const Value* n = r_.get(v, "fade_ms")) {
    if (auto ms = r_.number(*n, json::path_with_key(path, "fade_ms"), "fade_ms", 0, kMaxFadeMs, " ms"))
      out.fade_ms = *ms;
  }
  if (r_.count() != before) return false;
  s.action = out;
  return true;
}

bool StepChecker::wait(const Value& v, const std::string& path, Step& s) {
  if (!v.is(Kind::kObject)) {
    r_.wrong_type(v, path, "an object with ms or until_done");
    return false;
  }
  const size_t before = r_.count();
  r_.known_keys(v, path, kWaitKeys);
  const json::Member* ms = v.find("ms");
  const json::Member* until = v.find("until_done");
  WaitStep out;
  if (ms != nullptr && until != nullptr) {
    const json::Member& later = ms->at.offset > until->at.offset ? *ms : *until;
    r_.add(later.at, json::path_with_key(path, later.key), "either 'ms' or 'until_done'", r_.found(later),
           "a wait has either 'ms' or 'until_done', not both");
  } else if (ms != nullptr) {
    if (auto n = r_.number(ms->value, json::path_with_key(path, "ms"), "ms", 0, kMaxWaitMs, " ms")) out.ms = *n;
  } else if (until != nullptr) {
    if (auto names = motors_.motor_names(until->value, json::path_with_key(path, "until_done"))) {
      out.until_done = std::move(names->names);
    }
  } else if (r_.count() == before) {
    r_.add(v.at, json::path_with_key(path, "ms"), "'ms' (a pause) or 'until_done' (motor names)", "nothing",
           "a wait needs 'ms' or 'until_done'");
  }
  if (r_.count() != before) return false;
  s.action = std::move(out);
  return true;
}

// Returns the repeat's unrolled size, 0 when it is broken.
uint64_t StepChecker::repeat(const Value& v, const std::string& path, int repeat_depth, Step& s) {
  if (!v.is(Kind::kObject)) {
    r_.wrong_type(v, path, "an object with count and steps");
    return 0;
  }
  if (repeat_depth >= kMaxRepeatDepth) {
    r_.bad(v, path, "at most " + std::to_string(kMaxRepeatDepth) + " repeats inside one another",
           "repeats nest more than " + std::to_string(kMaxRepeatDepth) + " deep");
    return 0;
  }
  const size_t before = r_.count();
  r_.known_keys(v, path, kRepeatKeys);
  RepeatStep out;
  if (const Value* n = r_.get(v, "count")) {
    if (auto c = r_.integer(*n, json::path_with_key(path, "count"), "count", 1, kMaxRepeatCount)) out.count = *c;
  } else {
    r_.missing(v, path, "count", "a count from 1 to " + fmt(kMaxRepeatCount));
  }
  uint64_t inner = 0;
  if (const Value* n = r_.get(v, "steps")) {
    const std::string p = json::path_with_key(path, "steps");
    if (!n->is(Kind::kArray)) {
      r_.wrong_type(*n, p, "a list of steps");
    } else if (n->items.empty()) {
      r_.bad(*n, p, "a list of at least one step", "a repeat needs at least one step");
    } else {
      inner = steps(*n, p, repeat_depth + 1, out.steps);
    }
  } else {
    r_.missing(v, path, "steps", "a list of steps");
  }
  if (r_.count() != before) return 0;
  const uint64_t size = inner * out.count;
  if (size > kMaxUnrolledSteps) {
    r_.bad(v, path, "at most " + fmt(kMaxUnrolledSteps) + " steps once repeats are unrolled",
           "this repeat unrolls to " + fmt(static_cast<double>(size)) + " steps");
    return 0;
  }
  s.action = std::move(out);
  return size;
}

}  // namespace hmc::motion::reading
