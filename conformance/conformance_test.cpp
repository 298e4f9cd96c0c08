// The conformance runner: plays every vector in conformance/vectors/ against the firmware's
// FrameParser (byte by byte) and the host codec (line splitter + decode), and fails naming the
// vector and both verdicts when either parser disagrees with the vector or with the other, in
// the vector's checksum mode. Board -> host vectors (`board_line`) go to the host's
// decode_board_frame, and their canonical frames are held to what the firmware's reply writer
// writes. conformance/README.md defines the vector format.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/frame_parser.h"
#include "core/reply_writer.h"
#include "hmc/board_frame.h"
#include "hmc/codec.h"
#include "hmc/command_json.h"
#include "hmc/line_splitter.h"
#include "vector_input.h"
#include "core/testing/capture_port.h"

namespace {

using nlohmann::json;
namespace proto = hmc::proto;

// A verdict in the vector's own terms, so the vector and both parsers compare field by field.
json fw_command_json(const hmc::fw::Command& c) {
  const proto::CommandSpec& spec = proto::command_spec(c.id);
  uint32_t values[proto::kMaxValues] = {};
  const uint32_t count = hmc::fw::command_values(c, values);
  json out = {{"name", spec.name}};
  for (uint32_t i = 0; i < count; ++i) out[spec.fields[i].name] = values[i];
  return out;
}

json refused_json(proto::Reason reason, std::optional<int> token, std::size_t offset, uint32_t expected, uint32_t found) {
  return {{"verdict", "refused"},
          {"reason", proto::reason_spec(reason).name},
          {"token", token ? json(*token) : json(nullptr)},
          {"offset", offset},
          {"expected", expected},
          {"found", found}};
}

json fw_verdict_json(const hmc::fw::Verdict& v) {
  if (v.reason == proto::Reason::kOk) return {{"verdict", "accepted"}, {"command", fw_command_json(v.command)}};
  std::optional<int> token;
  if (v.token != proto::kNoToken) token = v.token;
  return refused_json(v.reason, token, v.offset, v.expected, v.found);
}

json host_verdict_json(const hmc::Result<hmc::Decoded, hmc::Diagnostic>& r) {
  if (r) return {{"verdict", "accepted"}, {"command", hmc::command_to_json(r->command)}};
  const hmc::Diagnostic& d = r.error();
  std::optional<int> token;
  if (d.token != hmc::kNoToken) token = d.token;
  return refused_json(d.reason, token, d.offset, d.expected, d.found);
}

// The vector's expectation reduced to what a parser verdict holds (absent expected/found are 0).
json expected_verdict(const json& e) {
  if (e.at("verdict") == "accepted") return {{"verdict", "accepted"}, {"command", e.at("command")}};
  if (e.at("verdict") == "ignored") return {{"verdict", "ignored"}};
  return {{"verdict", "refused"},
          {"reason", e.at("reason")},
          {"token", e.at("token")},
          {"offset", e.at("offset")},
          {"expected", e.value("expected", 0)},
          {"found", e.value("found", 0)}};
}

// The vector's checksum mode: "sum" (the default) or "crc16".
proto::ChecksumMode mode_of(const json& vector) {
  const std::string mode = vector.value("checksum_mode", "sum");
  REQUIRE((mode == "sum" || mode == "crc16"));
  return mode == "crc16" ? proto::ChecksumMode::kCrc16 : proto::ChecksumMode::kSum;
}

std::vector<json> firmware_verdicts(const std::string& stream, proto::ChecksumMode mode) {
  hmc::fw::FrameParser parser;
  parser.set_checksum_mode(mode);
  std::vector<json> out;
  for (char c : stream) {
    if (parser.feed(static_cast<uint8_t>(c))) out.push_back(fw_verdict_json(parser.verdict()));
  }
  return out;
}

// The host's verdicts for a stream delivered in two reads split at `cut`.
std::vector<json> host_verdicts(const std::string& stream, std::size_t cut, proto::ChecksumMode mode) {
  hmc::LineSplitter splitter;
  std::vector<json> out;
  auto drain = [&] {
    while (auto line = splitter.next()) out.push_back(host_verdict_json(hmc::decode(line->text, mode)));
  };
  splitter.feed(std::string_view(stream).substr(0, cut));
  drain();
  splitter.feed(std::string_view(stream).substr(cut));
  drain();
  return out;  // no finish(): like the board, a line without its end has no verdict yet
}

json as_list(const std::vector<json>& verdicts) {
  if (verdicts.empty()) return json::array({{{"verdict", "ignored"}}});
  return verdicts;
}

struct Tally {
  int vectors = 0, firmware_ok = 0, host_ok = 0, agree = 0;
  int board_lines = 0, board_host_ok = 0, board_written = 0, board_writer_ok = 0;
};

using hmc::testing::CapturePort;

json board_verdict_json(const hmc::Result<hmc::BoardFrame, hmc::Diagnostic>& r) {
  if (r) return {{"verdict", "accepted"}, {"frame", hmc::board_frame_to_json(*r)}, {"event", hmc::is_event(*r)}};
  const hmc::Diagnostic& d = r.error();
  std::optional<int> token;
  if (d.token != hmc::kNoToken) token = d.token;
  return refused_json(d.reason, token, d.offset, d.expected, d.found);
}

// A board -> host line: the host's decode_board_frame against the vector; a canonical accepted
// frame must also be what encode_board_frame and the firmware's reply writer write.
std::vector<std::string> check_board_line(const json& vector, Tally& tally) {
  std::vector<std::string> problems;
  const std::string id = vector.at("id");
  const std::string input = hmc::conformance::input_bytes(vector.at("input"));
  const proto::ChecksumMode mode = mode_of(vector);
  const json& expect = vector.at("expect");
  const json want = expect.at("verdict") == "accepted"
                        ? json{{"verdict", "accepted"}, {"frame", expect.at("frame")}, {"event", expect.at("event")}}
                        : expected_verdict(expect);
  const auto decoded = hmc::decode_board_frame(input, mode);
  const json host = board_verdict_json(decoded);
  ++tally.board_lines;
  tally.board_host_ok += host == want;
  if (host != want) problems.push_back(id + ": expected " + want.dump() + "\n    host: " + host.dump());
  if (decoded && expect.value("canonical", false)) {
    const auto again = hmc::encode_board_frame(*decoded, mode);
    if (!again || *again != input) {
      problems.push_back(id + ": encode_board_frame gave " + (again ? *again : again.error().message));
    }
    const auto values = hmc::board_frame_values(*decoded);
    // A frame as an older board writes it (VER before protocol 7): this firmware never does.
    if (values && values->count != hmc::board_frame_spec(*decoded).value_count) return problems;
    ++tally.board_written;
    CapturePort port;
    if (values) hmc::fw::write_frame(port, hmc::board_frame_id(*decoded), values->values.data(), mode);
    if (port.text == input + "\n") {
      ++tally.board_writer_ok;
    } else {
      problems.push_back(id + ": the firmware's reply writer writes " + port.text);
    }
  }
  return problems;
}

// Checks one vector; returns the mismatches found, each a line of text.
std::vector<std::string> check_vector(const json& vector, Tally& tally) {
  const std::string kind = vector.at("kind");
  if (kind == "board_line") return check_board_line(vector, tally);
  std::vector<std::string> problems;
  const std::string id = vector.at("id");
  const std::string input = hmc::conformance::input_bytes(vector.at("input"));
  const proto::ChecksumMode mode = mode_of(vector);
  const json& expect = vector.at("expect");

  json want;
  if (kind == "line") {
    want = json::array({expected_verdict(expect)});
  } else {
    want = json::array();
    for (const json& e : expect) want.push_back(expected_verdict(e));
    if (want.empty()) want.push_back({{"verdict", "ignored"}});
  }
  const std::string stream = kind == "line" ? input + "\n" : input;
  const json fw = as_list(firmware_verdicts(stream, mode));
  const json host = as_list(host_verdicts(stream, stream.size(), mode));

  ++tally.vectors;
  tally.firmware_ok += fw == want;
  tally.host_ok += host == want;
  tally.agree += fw == host;
  if (fw != want || host != want) {
    problems.push_back(id + ": expected " + want.dump() + "\n    firmware: " + fw.dump() + "\n    host:     " + host.dump());
  }
  for (std::size_t cut = 0; cut < stream.size() && kind == "stream"; ++cut) {
    if (as_list(host_verdicts(stream, cut, mode)) != host) problems.push_back(id + ": host verdicts change when the stream is split at byte " + std::to_string(cut));
  }

  // The host alone: canonical form, re-encoding and lint of accepted lines.
  if (kind == "line" && expect.at("verdict") == "accepted") {
    const auto decoded = hmc::decode(input, mode);
    if (decoded) {
      const std::string again = hmc::encode(decoded->command, mode).value();
      if (decoded->canonical != expect.at("canonical").get<bool>()) {
        problems.push_back(id + ": host says canonical=" + std::to_string(decoded->canonical));
      }
      if (expect.at("canonical").get<bool>() && again != input) {
        problems.push_back(id + ": encode(decode(input)) gave " + again);
      }
      if (!(hmc::decode(again, mode).ok() && hmc::decode(again, mode)->command == decoded->command)) {
        problems.push_back(id + ": the canonical form " + again + " does not decode to the same command");
      }
      std::vector<std::string> warned;
      for (const auto& w : decoded->warnings) warned.push_back(w.field);
      if (json(warned) != expect.value("warnings", json::array())) {
        problems.push_back(id + ": host warns about " + json(warned).dump());
      }
    }
  }
  if (vector.contains("as_input")) {
    const json& a = vector.at("as_input");
    const auto typed = hmc::parse_input(input, mode);
    if (a.at("verdict") == "accepted") {
      if (!typed) {
        problems.push_back(id + ": as input, refused: " + typed.error().message);
      } else {
        if (hmc::command_to_json(*typed) != a.at("command")) problems.push_back(id + ": as input, gave " + hmc::command_to_json(*typed).dump());
        const std::string framed = hmc::encode(*typed, mode).value();
        if (framed != a.at("frame")) problems.push_back(id + ": as input, framed as " + framed);
      }
    } else if (typed || proto::reason_spec(typed.error().reason).name != a.at("reason")) {
      problems.push_back(id + ": as input, expected refusal " + a.at("reason").dump() + ", got " +
                         (typed ? std::string("acceptance") : typed.error().message));
    }
  }
  return problems;
}

json load(const std::string& name) {
  std::ifstream in(std::filesystem::path(HMC_VECTORS_DIR) / name);
  REQUIRE(in.good());
  return json::parse(in);
}

void run_file(const std::string& name, std::size_t minimum_vectors) {
  const json file = load(name);
  const json& vectors = file.at("vectors");
  CHECK(vectors.size() >= minimum_vectors);
  Tally tally;
  for (const json& v : vectors) {
    const std::vector<std::string> problems = check_vector(v, tally);
    if (problems.empty()) SUCCEED(v.at("id").get<std::string>());
    for (const std::string& problem : problems) FAIL_CHECK(problem);
  }
  std::cout << name << ": " << tally.vectors << " vectors; firmware parser matches " << tally.firmware_ok
            << ", host codec matches " << tally.host_ok << ", parsers agree on " << tally.agree << "\n";
  if (tally.board_lines > 0) {
    std::cout << name << ": " << tally.board_lines << " board lines; host board decoder matches "
              << tally.board_host_ok << ", firmware reply writer writes " << tally.board_writer_ok << " of "
              << tally.board_written << " canonical frames\n";
  }
}

}  // namespace

TEST_CASE("vector ids are unique across all files") {
  std::set<std::string> ids;
  for (const auto& entry : std::filesystem::directory_iterator(HMC_VECTORS_DIR)) {
    const json file = load(entry.path().filename().string());
    for (const json& v : file.at("vectors")) {
      INFO(v.at("id"));
      CHECK(ids.insert(v.at("id").get<std::string>()).second);
    }
  }
}

TEST_CASE("spec examples: every frame printed in the spec") {
  const json file = load("spec_examples.json");
  int frames = 0, notation = 0;
  for (const json& v : file.at("vectors")) {
    (v.contains("as_input") ? notation : frames) += 1;
  }
  CHECK(frames == 28);
  CHECK(notation == 4);
  run_file("spec_examples.json", 32);
}

TEST_CASE("edge cases: our decisions on the spec's quirks") { run_file("edge_cases.json", 80); }

TEST_CASE("protocol v2: new commands, CRC-16 mode and board frames") {
  const json file = load("v2_frames.json");
  std::set<std::string> kinds, commands, board_frames;
  bool crc = false;
  for (const json& v : file.at("vectors")) {
    kinds.insert(v.at("kind").get<std::string>());
    crc = crc || v.value("checksum_mode", "sum") == "crc16";
    const json& e = v.at("expect");
    if (e.is_object() && e.at("verdict") == "accepted") {
      if (e.contains("command")) commands.insert(e.at("command").at("name").get<std::string>());
      if (e.contains("frame")) board_frames.insert(e.at("frame").at("name").get<std::string>());
    }
  }
  // Every v2 command and every board frame is accepted by some vector, in some mode.
  for (const auto& c : proto::kCommands) {
    if (c.id >= proto::CommandId::kVersion) CHECK(commands.count(c.name) == 1);
  }
  for (const auto& f : proto::kBoardFrames) CHECK(board_frames.count(f.name) == 1);
  CHECK(crc);
  CHECK(kinds == std::set<std::string>{"line", "stream", "board_line"});
  run_file("v2_frames.json", 150);
}
