// `hmc zero`: a resting motor's position set on the board, in the axis's units.
#include "zero_command.h"

#include <iostream>

#include "axis_units.h"
#include "exit_codes.h"
#include "hmc/units.h"
#include "profile_choice.h"

namespace hmc::cli {

void add_zero_command(CLI::App& app, const GlobalOptions& g, int& exit_code) {
  struct Options {
    std::string axis;
    std::string position = "0steps";
    uint32_t steps_per_rev = 200;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("zero", "set a resting motor's position: 0 here, or the position given (protocol 6)");
  cmd->add_option("axis", o->axis, "stepper 1-3, or an axis of the profile by name")->required();
  cmd->add_option("position", o->position, "where the axis is now: 100mm, -90deg, 2rev, 3200steps (default 0)");
  cmd->add_option("--steps-per-rev", o->steps_per_rev, "full steps per turn of a motor no profile axis drives (default 200)")
      ->check(CLI::Range(1u, 100000u));
  cmd->callback([&g, &exit_code, o] {
    const auto usage = [&g](const std::string& message) {
      report_error(g, SessionError{SessionError::Kind::kInvalid, message, proto::Reason::kOk});
      return static_cast<int>(kExitUsage);
    };
    Result<const Profile*, int> profile = use_profile(g);
    if (!profile) {
      exit_code = profile.error();
      return;
    }
    if (Result<Axis> known = resolve_axis(o->axis, *profile, BoardModel{}, o->steps_per_rev); !known) {
      exit_code = usage(known.error().message);
      return;
    }
    const std::string position_text = o->position == "0" ? "0steps" : o->position;
    Result<Quantity> quantity = parse_quantity(position_text);
    if (!quantity) {
      exit_code = usage("position: " + quantity.error().message);
      return;
    }
    std::unique_ptr<Session> s = connect(g, exit_code);
    if (!s) return;
    Result<Axis> axis = resolve_axis(o->axis, *profile, s->model(), o->steps_per_rev);
    Result<StepCount> steps = axis->to_steps(*quantity, Dimension::kPosition);
    if (!steps) {
      exit_code = usage("position: " + steps.error().message);
      return;
    }
    const double units = steps->exact / axis->steps_per_unit();
    if (steps->rounded() && !g.json) {
      std::cerr << "note: " << o->position << " on axis '" << axis->name << "' is " << number_text(steps->exact)
                << " steps: rounded to " << steps->steps << '\n';
    }
    if (SessionResult<BoardFrame> done = s->execute(set_position_command(*axis, units)); !done) {
      exit_code = report_error(g, done.error());
      return;
    }
    if (Status limits = send_soft_limits(*s, *axis); !limits) {
      exit_code = report_error(g, SessionError{SessionError::Kind::kNak, limits.error().message, proto::Reason::kOk});
      return;
    }
    if (g.json) {
      std::cout << nlohmann::json{{"axes", {axis_to_json(*axis, s->model().motor(axis->motor))}}} << '\n';
    } else {
      std::cout << axis_position_words(*axis, s->model().motor(axis->motor)) << '\n';
    }
    exit_code = kExitOk;
  });
}

}  // namespace hmc::cli
