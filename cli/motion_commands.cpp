// `hmc check | plan | run FILE`: motion files validated, planned (timeline, frames, velocity
// plots) and carried out on a board with progress, Ctrl-C stopping every motor, and --from.
#include "motion_commands.h"

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "exit_codes.h"
#include "profile_choice.h"
#include "hmc/codec.h"
#include "hmc/command_json.h"
#include "hmc/motion_file.h"
#include "hmc/motion_plan.h"
#include "hmc/motion_runner.h"

namespace hmc::cli {
namespace {

using motion::Plan;

void print_errors(const std::vector<motion::FileError>& errors, bool json) {
  if (json) {
    nlohmann::json list = nlohmann::json::array();
    for (const motion::FileError& e : errors) {
      list.push_back({{"file", e.where.file},
                      {"line", e.where.line},
                      {"column", e.where.column},
                      {"path", e.where.path},
                      {"expected", e.expected},
                      {"found", e.found},
                      {"message", e.message}});
    }
    std::cout << nlohmann::json{{"errors", list}} << '\n';
    return;
  }
  for (const motion::FileError& e : errors) std::cerr << e.text() << '\n';
  std::cerr << errors.size() << (errors.size() == 1 ? " error" : " errors") << "; nothing was sent\n";
}

// The file, read with the profile hmc uses (--profile, HMC_PROFILE or the default config: the
// axes of a file that names none), validated and planned; prints the errors and returns nothing
// when it is not valid. On failure `failure` is the exit code: a file that cannot be read is
// exit 3, a wrong one (or a wrong profile) 1.
std::optional<Plan> load_and_plan(const std::string& path, const motion::PlanOptions& options, const GlobalOptions& g,
                                  int& failure, motion::MotionFile* file_out = nullptr) {
  Result<const Profile*, int> in_use = use_profile(g);
  if (!in_use) {
    failure = in_use.error();
    return std::nullopt;
  }
  motion::ReadOptions read;
  read.profile = *in_use;
  if (Result<ProfileChoice> choice = choose_profile(g); *in_use != nullptr && choice && choice->from != "default") {
    read.profile_chosen_by = choice->from;
  }
  auto file = motion::load_motion_file(path, read);
  if (!file) {
    print_errors(file.error(), g.json);
    failure = std::ifstream(path) ? kExitInvalid : kExitIo;
    return std::nullopt;
  }
  // Values rounded to a whole step are no mistake, but the user should know where they are.
  for (const motion::FileError& n : file->notes) std::cerr << "note: " << n.text() << '\n';
  // The file's own profile is the run's from here: its link settings and soft limits.
  if (!file->profile.empty() && (*in_use == nullptr || (*in_use)->path != file->profile)) {
    Result<Profile, ProfileError> own = load_profile(file->profile);
    if (!own) {
      failure = report_profile_error(g, own.error());
      return std::nullopt;
    }
    adopt_profile(std::move(*own));
  }
  auto plan = motion::plan_motion(*file, options);
  if (!plan) {
    print_errors(plan.error(), g.json);
    failure = kExitInvalid;
    return std::nullopt;
  }
  if (file_out != nullptr) *file_out = std::move(*file);
  return std::move(*plan);
}

motion::TargetFirmware target_of(const GlobalOptions& g) {
  return g.firmware == "seed" ? motion::TargetFirmware::kSeed : motion::TargetFirmware::kV2;
}

std::string seconds(double s) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << s << " s";
  return out.str();
}

// Every frame of the plan with the time it is planned to be sent, in time order.
struct TimedFrame {
  double t_s;
  size_t action;
  std::string frame;
};

std::vector<TimedFrame> planned_frames(const Plan& plan) {
  std::vector<TimedFrame> frames;
  for (const motion::Action& a : plan.actions) {
    for (const Command& c : a.setup) frames.push_back({a.start_s, a.index, encode(c).value()});
    for (const auto& motor_stages : a.stages) {
      for (const motion::Stage& s : motor_stages) {
        const Command c = StepperMove{s.motor, s.dir, s.microstep, s.steps, s.delay_us};
        frames.push_back({s.start_s, a.index, encode(c).value()});
      }
    }
    for (size_t i = 0; i < a.commands.size(); ++i) {
      const double t = i < a.commands_at_s.size() ? a.commands_at_s[i] : a.start_s;
      frames.push_back({t, a.index, encode(a.commands[i]).value()});
    }
  }
  std::stable_sort(frames.begin(), frames.end(), [](const TimedFrame& x, const TimedFrame& y) { return x.t_s < y.t_s; });
  return frames;
}

void print_timeline(const Plan& plan) {
  std::cout << "step  start        duration     what\n";
  for (const motion::Action& a : plan.actions) {
    std::cout << std::left << std::setw(6) << a.index << std::setw(13) << seconds(a.start_s) << std::setw(13)
              << seconds(a.end_s - a.start_s) << a.description << '\n';
  }
  std::cout << "total " << seconds(plan.duration_s) << "; motors end at:";
  for (const motion::MotorTrack& t : plan.tracks) {
    std::cout << ' ' << t.name << " (motor " << t.motor << ") " << t.end_position << " steps;";
  }
  std::cout << '\n';
}

nlohmann::json plan_json(const Plan& plan) {
  nlohmann::json actions = nlohmann::json::array();
  for (const motion::Action& a : plan.actions) {
    actions.push_back({{"index", a.index},
                       {"start_s", a.start_s},
                       {"end_s", a.end_s},
                       {"description", a.description},
                       {"line", a.where.line}});
  }
  nlohmann::json tracks = nlohmann::json::array();
  for (const motion::MotorTrack& t : plan.tracks) {
    tracks.push_back({{"name", t.name},
                      {"motor", t.motor},
                      {"microstep", t.microstep},
                      {"start_position", t.start_position},
                      {"end_position", t.end_position}});
  }
  nlohmann::json frames = nlohmann::json::array();
  for (const TimedFrame& f : planned_frames(plan)) frames.push_back({{"t_s", f.t_s}, {"step", f.action}, {"frame", f.frame}});
  return {{"duration_s", plan.duration_s}, {"actions", actions}, {"motors", tracks}, {"frames", frames}};
}

bool write_file(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  if (!out) {
    std::cerr << "error: cannot write " << path << '\n';
    return false;
  }
  return true;
}

// --- check, plan ----------------------------------------------------------------------------

void add_check(CLI::App& app, const GlobalOptions& g, int& exit_code) {
  auto path = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand("check", "validate a motion file: every mistake, with line and column");
  cmd->add_option("file", *path, "the motion file (docs/motion-files.md)")->required();
  cmd->callback([&g, &exit_code, path] {
    motion::PlanOptions options;
    options.firmware = target_of(g);
    motion::MotionFile file;
    std::optional<Plan> plan = load_and_plan(*path, options, g, exit_code, &file);
    if (!plan) {
      return;
    }
    if (g.json) {
      std::cout << nlohmann::json{{"file", *path}, {"valid", true}, {"actions", plan->actions.size()},
                                  {"duration_s", plan->duration_s}}
                << '\n';
    } else {
      std::cout << *path << ": valid: " << file.steps.size() << " steps, " << plan->actions.size()
                << " actions unrolled, about " << seconds(plan->duration_s) << '\n';
    }
  });
}

void add_plan(CLI::App& app, const GlobalOptions& g, int& exit_code) {
  struct Options {
    std::string path, svg, csv;
    bool frames = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("plan", "show what a motion file will do: timeline, frames, velocity plots");
  cmd->add_option("file", o->path, "the motion file")->required();
  cmd->add_option("--plot", o->svg, "write velocity over time per motor as an SVG picture");
  cmd->add_option("--csv", o->csv, "write the velocity data as CSV (t_s,motor,name,velocity)");
  cmd->add_flag("--frames", o->frames, "also list every frame with its planned send time");
  cmd->callback([&g, &exit_code, o] {
    motion::PlanOptions options;
    options.firmware = target_of(g);
    options.baud = g.baud;
    motion::MotionFile file;
    std::optional<Plan> plan = load_and_plan(o->path, options, g, exit_code, &file);
    if (!plan) {
      return;
    }
    if (!o->svg.empty() && !write_file(o->svg, motion::plot_svg(*plan, file.name.empty() ? o->path : file.name))) {
      exit_code = kExitIo;
      return;
    }
    if (!o->csv.empty() && !write_file(o->csv, motion::plot_csv(*plan))) {
      exit_code = kExitIo;
      return;
    }
    if (g.json) {
      std::cout << plan_json(*plan).dump(2) << '\n';
      return;
    }
    print_timeline(*plan);
    if (o->frames) {
      for (const TimedFrame& f : planned_frames(*plan)) {
        std::cout << std::setw(12) << seconds(f.t_s) << "  [" << f.action << "]  " << f.frame << '\n';
      }
    }
    if (!o->svg.empty()) std::cout << "plot: " << o->svg << '\n';
  });
}

// --- run ------------------------------------------------------------------------------------

// Progress: one redrawn line on a terminal, plain lines otherwise, JSON lines with --json.
class Progress {
 public:
  explicit Progress(bool json) : json_(json), terminal_(!json && isatty(STDERR_FILENO) == 1) {}

  void operator()(const motion::RunEvent& e) {
    if (json_) {
      nlohmann::json j{{"event", e.kind == motion::RunEvent::Kind::kActionStarted ? "started"
                                 : e.kind == motion::RunEvent::Kind::kActionDone  ? "done"
                                                                                   : "returning"},
                       {"total", e.total},
                       {"elapsed_s", e.elapsed_s},
                       {"remaining_s", e.remaining_s}};
      if (e.action != nullptr) {
        j["step"] = e.action->index;
        j["description"] = e.action->description;
      }
      std::cout << j << std::endl;
      return;
    }
    if (e.kind == motion::RunEvent::Kind::kReturning) {
      finish_line();
      std::cerr << "returning the motors to where the plan has them at the resumed step\n";
      return;
    }
    if (e.kind == motion::RunEvent::Kind::kActionDone && !terminal_) return;
    std::ostringstream line;
    line << "step " << e.action->index << " of " << e.total << "  " << std::fixed << std::setprecision(1)
         << e.elapsed_s << " s elapsed, ~" << e.remaining_s << " s left  " << e.action->description;
    if (!terminal_) {
      std::cerr << line.str() << '\n';
      return;
    }
    const size_t width = 24;
    const size_t filled = e.total == 0 ? width : width * (e.action->index - (e.kind == motion::RunEvent::Kind::kActionDone ? 0 : 1)) / e.total;
    std::string text = "[" + std::string(filled, '#') + std::string(width - filled, '.') + "] " + line.str();
    if (text.size() > 110) text = text.substr(0, 107) + "...";
    std::cerr << "\r\033[K" << text << std::flush;
    open_ = true;
  }

  void finish_line() {
    if (open_) std::cerr << '\n';
    open_ = false;
  }

 private:
  bool json_;
  bool terminal_;
  bool open_ = false;
};

void add_run(CLI::App& app, const GlobalOptions& g, int& exit_code) {
  struct Options {
    std::string path;
    bool dry_run = false;
    size_t from = 1;
    std::string at;  // where the motors were when the file first started: "0,-,25600"
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("run", "run a motion file on the board (validated first; Ctrl-C stops every motor)");
  cmd->add_option("file", o->path, "the motion file")->required();
  cmd->add_flag("--dry-run", o->dry_run, "print the timeline and the exact frames; no board");
  cmd->add_option("--from", o->from, "start at this step (as numbered by the plan, from 1; after an interruption)")
      ->check(CLI::Validator(
          [](const std::string& text) {
            return text.find_first_not_of("0123456789") == std::string::npos && text.find_first_not_of('0') != std::string::npos
                       ? std::string()
                       : "--from takes a step number, 1 or more, not '" + text + "'";
          },
          "STEP"));
  cmd->add_option("--at", o->at,
                  "with --from: where motors 1,2,3 were (steps, a fraction as printed; - unknown) when the file first "
                  "started, as the interrupted run printed; they are first moved to where the plan has them at that step");
  cmd->callback([&g, &exit_code, o] {
    motion::PlanOptions options;
    options.firmware = target_of(g);
    options.baud = g.baud;
    if (o->dry_run) {
      std::optional<Plan> plan = load_and_plan(o->path, options, g, exit_code);
      if (!plan) {
        return;
      }
      if (g.json) {
        std::cout << plan_json(*plan).dump(2) << '\n';
        return;
      }
      print_timeline(*plan);
      std::cout << "\nframes (planned send time, step):\n";
      for (const TimedFrame& f : planned_frames(*plan)) {
        std::cout << std::setw(12) << seconds(f.t_s) << "  [" << f.action << "]  " << f.frame << '\n';
      }
      return;
    }
    // Validate before touching the port: a file with mistakes never reaches the board.
    motion::MotionFile file;
    if (!load_and_plan(o->path, options, g, exit_code, &file)) {
      return;
    }
    if (!o->at.empty()) {
      // Resuming: the plan starts where the first run started. A usage error, found before the
      // port is opened.
      std::vector<std::string> items;
      std::stringstream list(o->at);
      for (std::string item; std::getline(list, item, ',');) items.push_back(item);
      if (o->at.back() == ',') items.push_back("");
      std::string problem;
      if (items.size() != proto::kMotorCount) {
        problem = "--at takes " + std::to_string(proto::kMotorCount) + " values, motors 1,2,3 (steps, or - for unknown), not " +
                  std::to_string(items.size()) + ": '" + o->at + "'";
      }
      for (uint32_t m = 1; problem.empty() && m <= items.size(); ++m) {
        const std::string& item = items[m - 1];
        if (item == "-") continue;
        // Steps at the motor's microstep, as the interrupted run printed them: a fraction when the
        // motor stood between two steps.
        char* end = nullptr;
        const double v = std::strtod(item.c_str(), &end);
        if (item.empty() || *end != '\0' || !std::isfinite(v) || std::fabs(v) > 1e15) {
          problem = "--at: '" + item + "' (motor " + std::to_string(m) + ") is not a number of steps or -";
        } else {
          options.start_position[m - 1] = v;
        }
      }
      if (!problem.empty()) {
        report_error(g, SessionError{SessionError::Kind::kInvalid, problem, proto::Reason::kOk});
        exit_code = kExitUsage;
        return;
      }
    }
    std::unique_ptr<Session> session = connect(g, exit_code);
    if (!session) return;
    options.firmware = session->firmware() == Firmware::kV2 ? motion::TargetFirmware::kV2 : motion::TargetFirmware::kSeed;
    options.budgets = session->step_budgets_in_force();
    // Absolute moves start from where the board says each motor is, unless --at gave where the
    // motors were when the file first started.
    if (o->at.empty()) motion::start_where_board_is(*session, file, options);
    auto plan = motion::plan_motion(file, options);
    if (!plan) {
      print_errors(plan.error(), g.json);
      exit_code = kExitInvalid;
      return;
    }
    if (o->from > plan->actions.size()) {
      exit_code = report_error(g, SessionError{SessionError::Kind::kInvalid,
                                               "--from " + std::to_string(o->from) + ": the plan has only " +
                                                   std::to_string(plan->actions.size()) + " steps",
                                               proto::Reason::kOk});
      return;
    }
    if (SessionResult<Done> watched = watch_link(*session, g); !watched) {
      exit_code = report_error(g, watched.error());
      return;
    }
    Progress progress(g.json);
    motion::RunOptions run_options;
    run_options.from = o->from;
    run_options.resume = !o->at.empty();
    run_options.on_event = [&progress](const motion::RunEvent& e) { progress(e); };
    motion::MotionRunner runner(*session, *plan);
    const motion::RunReport report = runner.run(run_options);
    progress.finish_line();
    if (report.error) {
      exit_code = report_error(g, *report.error);
      const motion::Action& at = plan->actions[report.stopped_at - 1];
      if (g.json) {
        std::cout << nlohmann::json{{"stopped_at", report.stopped_at}, {"state", model_to_json(*session)}} << '\n';
      } else {
        std::cerr << "stopped during step " << report.stopped_at << " of " << plan->actions.size() << " ("
                  << at.description << ", " << o->path << ":" << at.where.line << ")\n";
        for (const MotorStatus& m : session->model().motors) std::cerr << "  motor " << m.motor << " " << position_words(m) << '\n';
        std::string origin;
        for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
          const std::optional<double>& p = options.start_position[m - 1];
          origin += (m > 1 ? "," : "") + (p ? number_text(*p, 8) : std::string("-"));
        }
        std::cerr << "resume with: hmc run " << o->path << " --from " << report.stopped_at
                  << (session->firmware() == Firmware::kV2 ? " --at " + origin : std::string()) << '\n';
      }
      return;
    }
    if (g.json) {
      std::cout << nlohmann::json{{"completed", report.completed}, {"state", model_to_json(*session)}} << '\n';
    } else if (session->firmware() == Firmware::kSeed) {
      // Nothing came back: what was sent, and where the motors are only if the board obeyed.
      std::cout << "sent every step (" << report.completed << "); the original firmware confirms nothing";
      for (const motion::MotorTrack& t : plan->tracks) {
        std::cout << "; if it obeyed, " << t.name << " is " << seed_position_words(session->model().motor(t.motor));
      }
      std::cout << '\n';
    } else {
      std::cout << "done: " << report.completed << " steps";
      for (const motion::MotorTrack& t : plan->tracks) {
        std::cout << "; " << t.name << " " << position_words(session->model().motor(t.motor));
      }
      std::cout << '\n';
    }
  });
}

}  // namespace

void add_motion_commands(CLI::App& app, const GlobalOptions& global, int& exit_code) {
  add_check(app, global, exit_code);
  add_plan(app, global, exit_code);
  add_run(app, global, exit_code);
}

}  // namespace hmc::cli
