// `hmc frame encode|decode|check`: build frames, explain frames, check files of frames.
#include "frame_command.h"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>

#include "exit_codes.h"
#include "hmc/codec.h"
#include "hmc/command_json.h"
#include "hmc/line_splitter.h"
#include "report.h"

namespace hmc::cli {
namespace {

struct FrameOptions {
  std::string first;                // a command name, a frame or notation; kept whole
  std::vector<std::string> values;  // the values after a command name
  std::string frame;
  std::string file;
  bool json = false;
  bool quiet = false;
};

// A lone argument holding '#' is a frame or notation; otherwise NAME v1 ... vn.
Result<Command, Diagnostic> command_from_arguments(const FrameOptions& o) {
  if (o.values.empty() && o.first.find('#') != std::string::npos) return parse_input(o.first);
  std::vector<std::string> words{o.first};
  words.insert(words.end(), o.values.begin(), o.values.end());
  return command_from_words(words);
}

int run_encode(const FrameOptions& o) {
  auto command = command_from_arguments(o);
  if (!command) {
    if (o.json) {
      std::cout << nlohmann::json{{"verdict", "refused"}, {"error", diagnostic_to_json(command.error())}} << "\n";
    } else {
      print_refusal(std::cerr, o.values.empty() ? o.first : "", command.error());
    }
    return kExitInvalid;
  }
  const std::string frame = encode(*command).value();  // parse_input and command_from_words validate
  const std::vector<Warning> warnings = lint(*command);
  if (o.json) {
    std::cout << nlohmann::json{{"verdict", "accepted"}, {"frame", frame}, {"command", command_to_json(*command)},
                                {"warnings", warnings_to_json(warnings)}}
              << "\n";
  } else {
    print_warnings(std::cerr, warnings);
    std::cout << frame << "\n";
  }
  return kExitOk;
}

nlohmann::json verdict_json(const Result<Decoded, Diagnostic>& r) {
  if (!r) return {{"verdict", "refused"}, {"error", diagnostic_to_json(r.error())}};
  return {{"verdict", "accepted"},
          {"command", command_to_json(r->command)},
          {"canonical", r->canonical},
          {"warnings", warnings_to_json(r->warnings)}};
}

int run_decode(const FrameOptions& o) {
  const auto r = decode(o.frame);
  if (o.json) {
    nlohmann::json out = verdict_json(r);
    out["input"] = o.frame;
    std::cout << out.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
  } else if (r) {
    print_command(std::cout, r->command);
    if (!r->canonical) std::cout << "  canonical form: " << encode(r->command).value() << "\n";
    print_warnings(std::cout, r->warnings);
  } else {
    print_refusal(std::cout, o.frame, r.error());
  }
  return r ? kExitOk : kExitInvalid;
}

int run_check(const FrameOptions& o) {
  std::istream* in = &std::cin;
  std::unique_ptr<std::ifstream> file;
  if (o.file != "-") {
    file = std::make_unique<std::ifstream>(o.file, std::ios::binary);
    if (!*file) {
      std::cerr << "error: cannot read '" << o.file << "': " << std::strerror(errno) << "\n";
      return kExitIo;
    }
    in = file.get();
  }
  LineSplitter splitter;
  std::size_t valid = 0, invalid = 0;
  auto judge_ready_lines = [&] {
    while (auto line = splitter.next()) {
      const auto r = decode(line->text);
      r ? ++valid : ++invalid;
      if (o.json) {
        nlohmann::json out = verdict_json(r);
        out["line"] = line->number;
        std::cout << out.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
      } else if (!r) {
        std::cout << o.file << ":" << line->number << ": ";
        print_refusal(std::cout, line->text, r.error());
      } else if (!o.quiet) {
        std::cout << o.file << ":" << line->number << ": ok: " << line->text << "  (" << describe(r->command) << ")\n";
        for (const Warning& w : r->warnings) std::cout << o.file << ":" << line->number << ": warning: " << w.message << "\n";
      }
    }
  };
  char buffer[4096];
  while (in->read(buffer, sizeof buffer) || in->gcount() > 0) {
    splitter.feed(std::string_view(buffer, static_cast<std::size_t>(in->gcount())));
    judge_ready_lines();
  }
  splitter.finish();
  judge_ready_lines();
  if (!o.json) {
    std::cerr << valid + invalid << " frames: " << valid << " valid, " << invalid << " invalid\n";
  }
  return invalid == 0 ? kExitOk : kExitInvalid;
}

}  // namespace

void add_frame_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<FrameOptions>();
  CLI::App* frame = app.add_subcommand("frame", "Build, explain and check protocol frames (no board needed)");
  frame->require_subcommand(1);

  CLI::App* enc = frame->add_subcommand("encode", "Frame a command: length and checksum filled in");
  enc->add_option("command", options->first, "A command name (STM, SVM, LED), '[#NAME#v1#...]' or a frame")
      ->required();
  enc->add_option("values", options->values, "The command's values, in wire order");
  enc->add_flag("--json", options->json, "Print JSON");
  enc->footer("Examples:\n  hmc frame encode STM 1 1 128 1000 500\n  hmc frame encode '[#SVM#1#135]'");
  enc->callback([options, &exit_code] { exit_code = run_encode(*options); });

  CLI::App* dec = frame->add_subcommand("decode", "Explain a frame: its fields, or what is wrong and where");
  dec->add_option("frame", options->frame, "A frame, e.g. 'STX#3#SVM#1#10#11#ETX'")->required();
  dec->add_flag("--json", options->json, "Print JSON");
  dec->footer("Example:\n  hmc frame decode 'STX#6#STM#3#1#1#11#1000#238#ETX'");
  dec->callback([options, &exit_code] { exit_code = run_decode(*options); });

  CLI::App* chk = frame->add_subcommand("check", "Check a file of frames, one per line; a verdict per line");
  chk->add_option("file", options->file, "File to check, or - for standard input")->required();
  chk->add_flag("--json", options->json, "Print one JSON object per line");
  chk->add_flag("-q,--quiet", options->quiet, "Print only invalid lines");
  chk->footer("Example:\n  hmc frame check examples/spec-frames.txt");
  chk->callback([options, &exit_code] { exit_code = run_check(*options); });
}

}  // namespace hmc::cli
