// `hmc config`: the machine profile's path, its contents as understood, and its mistakes.
#include "config_command.h"

#include <iostream>

#include "exit_codes.h"
#include "profile_choice.h"

namespace hmc::cli {
namespace {

// "belt: 20 teeth x 2 mm = 40 mm per turn" and the like, from the axis as read.
std::string drive_words(const Axis& a) {
  if (a.rotary) return "rotary";
  return "linear, " + number_text(a.mm_per_rev, 4) + " mm per turn";
}

nlohmann::json optional_json(const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); }

nlohmann::json axis_json(const Axis& a) {
  nlohmann::json j{{"name", a.name},
                   {"motor", a.motor},
                   {"unit", unit_name(a.unit())},
                   {"steps_per_rev", a.steps_per_rev},
                   {"microstep", a.microstep},
                   {"gear_ratio", a.gear_ratio},
                   {"rotary", a.rotary},
                   {"mm_per_rev", a.rotary ? nlohmann::json(nullptr) : nlohmann::json(a.mm_per_rev)},
                   {"invert", a.invert},
                   {"steps_per_unit", a.steps_per_unit()},
                   {"limits", a.limit_min ? nlohmann::json{*a.limit_min, *a.limit_max} : nlohmann::json(nullptr)},
                   {"speed", optional_json(a.speed)},
                   {"accel", optional_json(a.accel)},
                   {"line", a.place.line}};
  if (a.homing) {
    j["homing"] = {{"end", a.homing->end == 0 ? "reverse" : "forward"},
                   {"seek_speed", optional_json(a.homing->seek_speed)},
                   {"pull_off", optional_json(a.homing->pull_off)},
                   {"locate_speed", optional_json(a.homing->locate_speed)}};
  } else {
    j["homing"] = nullptr;
  }
  return j;
}

void print_axis(const Axis& a) {
  const std::string u = unit_name(a.unit());
  std::cout << "axis " << a.name << " (motor " << a.motor << "): " << drive_words(a) << "; " << a.steps_per_rev
            << " steps per turn at 1/" << a.microstep;
  if (a.gear_ratio != 1) std::cout << ", gear " << number_text(a.gear_ratio, 4) << ":1";
  std::cout << " = " << number_text(a.steps_per_unit(), 4) << " steps per " << u << (a.invert ? ", inverted" : "")
            << '\n';
  if (a.limit_min) std::cout << "  limits " << number_text(*a.limit_min) << " to " << number_text(*a.limit_max) << ' ' << u << '\n';
  if (a.speed) std::cout << "  speed " << number_text(*a.speed) << ' ' << u << "/s\n";
  if (a.accel) std::cout << "  accel " << number_text(*a.accel) << ' ' << u << "/s2\n";
  if (a.homing) {
    std::cout << "  homes toward the " << (a.homing->end == 0 ? "reverse" : "forward") << " switch";
    if (a.homing->seek_speed) std::cout << " at " << number_text(*a.homing->seek_speed) << ' ' << u << "/s";
    if (a.homing->pull_off) std::cout << ", pulls off " << number_text(*a.homing->pull_off) << ' ' << u;
    if (a.homing->locate_speed) std::cout << ", locates at " << number_text(*a.homing->locate_speed) << ' ' << u << "/s";
    std::cout << '\n';
  }
}

}  // namespace

void add_config_command(CLI::App& app, const GlobalOptions& g, int& exit_code) {
  CLI::App* config = app.add_subcommand("config", "the machine profile: where it is, what it says, its mistakes");
  config->require_subcommand(1);

  CLI::App* path_cmd = config->add_subcommand("path", "where the profile is looked for, and whether it exists");
  path_cmd->callback([&g, &exit_code] {
    Result<ProfileChoice> choice = choose_profile(g);
    if (!choice) {
      exit_code = report_error(g, SessionError{SessionError::Kind::kLink, choice.error().message, proto::Reason::kOk});
      return;
    }
    if (g.json) {
      std::cout << nlohmann::json{{"path", choice->path}, {"from", choice->from}, {"exists", choice->exists}} << '\n';
      return;
    }
    std::cout << choice->path << '\n';
    std::cerr << "(" << (choice->from == "default" ? "the default" : "from " + choice->from) << "; "
              << (choice->exists ? "it exists" : "it does not exist") << ")\n";
  });

  CLI::App* show_cmd = config->add_subcommand("show", "the profile as understood: port, and each axis in steps per unit");
  show_cmd->callback([&g, &exit_code] {
    Result<const Profile*, int> p = use_profile(g);
    if (!p) {
      exit_code = p.error();
      return;
    }
    if (*p == nullptr) {
      Result<ProfileChoice> choice = choose_profile(g);
      exit_code = report_error(g, SessionError{SessionError::Kind::kLink,
                                               "no profile: " + (choice ? choice->path : std::string("the default")) +
                                                   " does not exist (docs/config.md; examples/*.toml)",
                                               proto::Reason::kOk});
      return;
    }
    const Profile& profile = **p;
    if (g.json) {
      nlohmann::json axes = nlohmann::json::array();
      for (const Axis& a : profile.axes) axes.push_back(axis_json(a));
      std::cout << nlohmann::json{{"path", profile.path},
                                  {"port", profile.port ? nlohmann::json(*profile.port) : nlohmann::json(nullptr)},
                                  {"baud", profile.baud ? nlohmann::json(*profile.baud) : nlohmann::json(nullptr)},
                                  {"firmware", profile.firmware ? nlohmann::json(*profile.firmware) : nlohmann::json(nullptr)},
                                  {"axes", axes}}
                       .dump(2)
                << '\n';
      return;
    }
    std::cout << "profile " << profile.path << '\n';
    std::cout << "port " << profile.port.value_or("(not set: --port, HMC_PORT, or the one board found)") << ", baud "
              << (profile.baud ? std::to_string(*profile.baud) : std::string("(not set)")) << ", firmware "
              << profile.firmware.value_or("(not set: auto)") << '\n';
    for (const Axis& a : profile.axes) print_axis(a);
  });

  auto file = std::make_shared<std::string>();
  CLI::App* check_cmd = config->add_subcommand("check", "check a profile: every mistake, with line and column");
  check_cmd->add_option("file", *file, "the profile (default: the one in use, as `hmc config path` says)");
  check_cmd->callback([&g, &exit_code, file] {
    std::string path = *file;
    if (path.empty()) {
      Result<ProfileChoice> choice = choose_profile(g);
      if (!choice) {
        exit_code = report_error(g, SessionError{SessionError::Kind::kLink, choice.error().message, proto::Reason::kOk});
        return;
      }
      path = choice->path;
    }
    Result<Profile, ProfileError> profile = load_profile(path);
    if (!profile) {
      exit_code = report_profile_error(g, profile.error());
      return;
    }
    if (g.json) {
      std::cout << nlohmann::json{{"file", path}, {"valid", true}, {"axes", profile->axes.size()}} << '\n';
      return;
    }
    std::cout << path << ": valid: " << profile->axes.size() << (profile->axes.size() == 1 ? " axis" : " axes");
    for (size_t i = 0; i < profile->axes.size(); ++i) {
      std::cout << (i == 0 ? " (" : ", ") << profile->axes[i].name;
    }
    std::cout << (profile->axes.empty() ? "" : ")") << '\n';
  });
}

}  // namespace hmc::cli
