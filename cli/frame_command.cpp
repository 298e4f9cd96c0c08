// `hmc frame encode|decode|check`: build frames, explain frames, check files of frames, in
// either checksum mode (--crc), and read frames the board sends (--board).
#include "frame_command.h"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>
#include <type_traits>

#include "exit_codes.h"
#include "hmc/board_frame.h"
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
  bool crc = false;    // CRC-16 checksums (after CRC 1), not the seed's sum
  bool board = false;  // frames the board sends (replies and events), not commands

  proto::ChecksumMode mode() const { return crc ? proto::ChecksumMode::kCrc16 : proto::ChecksumMode::kSum; }
};

// The names of the commands, for help texts: "STM, SVM, LED, VER, ...".
std::string command_names() {
  std::string out;
  for (const auto& spec : proto::kCommands) out += (out.empty() ? "" : ", ") + std::string(spec.name);
  return out;
}

// A lone argument is a frame, notation or a quoted `NAME v1 ... vn`; otherwise the words.
Result<Command, Diagnostic> command_from_arguments(const FrameOptions& o) {
  if (o.values.empty()) return command_from_text(o.first, o.mode());
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
  const std::string frame = encode(*command, o.mode()).value();  // parse_input and command_from_words validate
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

nlohmann::json verdict_json(const Result<BoardFrame, Diagnostic>& r) {
  if (!r) return {{"verdict", "refused"}, {"error", diagnostic_to_json(r.error())}};
  return {{"verdict", "accepted"}, {"frame", board_frame_to_json(*r)}, {"event", is_event(*r)}};
}

// One line's verdict, printed for a person (decode) or as JSON; returns whether it was accepted.
template <typename Verdict>
bool report_line(const FrameOptions& o, std::string_view line, const Verdict& r) {
  if (o.json) {
    nlohmann::json out = verdict_json(r);
    out["input"] = line;
    std::cout << out.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
  } else if (!r) {
    print_refusal(std::cout, line, r.error());
  } else if constexpr (std::is_same_v<Verdict, Result<Decoded, Diagnostic>>) {
    print_command(std::cout, r->command, o.mode());
    if (!r->canonical) std::cout << "  canonical form: " << encode(r->command, o.mode()).value() << "\n";
    print_warnings(std::cout, r->warnings);
  } else {
    print_board_frame(std::cout, *r);
  }
  return r.ok();
}

int run_decode(const FrameOptions& o) {
  const bool accepted = o.board ? report_line(o, o.frame, decode_board_frame(o.frame, o.mode()))
                                : report_line(o, o.frame, decode(o.frame, o.mode()));
  return accepted ? kExitOk : kExitInvalid;
}

// "(description)" of an accepted line, for `check`.
std::string described(const Result<Decoded, Diagnostic>& r) { return describe(r->command); }
std::string described(const Result<BoardFrame, Diagnostic>& r) { return describe(*r); }
std::vector<Warning> warnings_of(const Result<Decoded, Diagnostic>& r) { return r->warnings; }
std::vector<Warning> warnings_of(const Result<BoardFrame, Diagnostic>&) { return {}; }

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
  auto judge = [&](const Line& line, const auto& r) {
    r ? ++valid : ++invalid;
    if (o.json) {
      nlohmann::json out = verdict_json(r);
      out["line"] = line.number;
      std::cout << out.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
    } else if (!r) {
      std::cout << o.file << ":" << line.number << ": ";
      print_refusal(std::cout, line.text, r.error());
    } else if (!o.quiet) {
      std::cout << o.file << ":" << line.number << ": ok: " << line.text << "  (" << described(r) << ")\n";
      for (const Warning& w : warnings_of(r)) {
        std::cout << o.file << ":" << line.number << ": warning: " << w.message << "\n";
      }
    }
  };
  auto judge_ready_lines = [&] {
    while (auto line = splitter.next()) {
      if (o.board) {
        judge(*line, decode_board_frame(line->text, o.mode()));
      } else {
        judge(*line, decode(line->text, o.mode()));
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
  enc->add_option("command", options->first, "A command name (" + command_names() + "), '[#NAME#v1#...]' or a frame")
      ->required();
  enc->add_option("values", options->values, "The command's values, in wire order");
  enc->add_flag("--json", options->json, "Print JSON");
  enc->add_flag("--crc", options->crc, "CRC-16 checksum (the board's mode after CRC 1), not the seed's sum");
  enc->footer(
      "Examples:\n  hmc frame encode STM 1 1 128 1000 500\n  hmc frame encode '[#SVM#1#135]'\n"
      "  hmc frame encode VER\n  hmc frame encode SET 1 3 8000\n  hmc frame encode --crc CRC 0");
  enc->callback([options, &exit_code] { exit_code = run_encode(*options); });

  CLI::App* dec = frame->add_subcommand("decode", "Explain a frame: its fields, or what is wrong and where");
  dec->add_option("frame", options->frame, "A frame, e.g. 'STX#3#SVM#1#10#11#ETX'")->required();
  dec->add_flag("--json", options->json, "Print JSON");
  dec->add_flag("--crc", options->crc, "CRC-16 checksums (the board's mode after CRC 1), not the seed's sum");
  dec->add_flag("--board", options->board, "A frame the board sends (ACK, NAK, VER, STA, ..., events EV*)");
  dec->footer(
      "Examples:\n  hmc frame decode 'STX#6#STM#3#1#1#11#1000#238#ETX'\n"
      "  hmc frame decode --board 'STX#4#NAK#8#8#24#40#ETX'");
  dec->callback([options, &exit_code] { exit_code = run_decode(*options); });

  CLI::App* chk = frame->add_subcommand("check", "Check a file of frames, one per line; a verdict per line");
  chk->add_option("file", options->file, "File to check, or - for standard input")->required();
  chk->add_flag("--json", options->json, "Print one JSON object per line");
  chk->add_flag("-q,--quiet", options->quiet, "Print only invalid lines");
  chk->add_flag("--crc", options->crc, "CRC-16 checksums (the board's mode after CRC 1), not the seed's sum");
  chk->add_flag("--board", options->board, "Frames the board sends (a captured session's replies and events)");
  chk->footer("Example:\n  hmc frame check examples/spec-frames.txt");
  chk->callback([options, &exit_code] { exit_code = run_check(*options); });
}

}  // namespace hmc::cli
