// The firmware's reply writer against the host's board-frame decoder: for every board frame, in
// both checksum modes, the line fw::write_frame() writes decodes (decode_board_frame) to the
// values it was given, and the host's encode_board_frame() writes the very same line. Values run
// over every field's range edges and random values within the ranges (a setting's value within
// that setting's range).
#include <catch2/catch.hpp>

#include <random>
#include <string>
#include <vector>

#include "core/reply_writer.h"
#include "hmc/board_frame.h"
#include "core/testing/capture_port.h"

namespace {

namespace proto = hmc::proto;

using hmc::testing::CapturePort;

// The range a field's value may take, given the values before it.
void range_of(const proto::FieldSpec& field, const std::vector<uint32_t>& before, uint32_t& min, uint32_t& max) {
  min = field.min;
  max = field.max;
  if ((field.flags & proto::kSettingValue) != 0) {
    const proto::SettingSpec& setting = proto::kSettings[before.back() - 1];
    min = setting.min;
    max = setting.max;
  }
}

// Values for a frame: `pick` chooses each value within its range. A magnitude after a sign of 1
// is at least 1: the board never writes minus zero (fw::put_signed).
template <typename Pick>
std::vector<uint32_t> values_for(const proto::BoardFrameSpec& spec, Pick pick) {
  std::vector<uint32_t> values;
  for (uint32_t i = 0; i < spec.value_count; ++i) {
    uint32_t min = 0, max = 0;
    range_of(spec.fields[i], values, min, max);
    const bool after_minus = i > 0 && std::string(spec.fields[i - 1].name).find("sign") != std::string::npos &&
                             values.back() == 1;
    if (after_minus && min == 0) min = 1;
    values.push_back(pick(min, max));
  }
  return values;
}

void check_round_trip(const proto::BoardFrameSpec& spec, const std::vector<uint32_t>& values,
                      proto::ChecksumMode mode) {
  CapturePort port;
  hmc::fw::write_frame(port, spec.id, values.data(), mode);
  INFO("firmware wrote " << port.text);
  REQUIRE(!port.text.empty());
  REQUIRE(port.text.back() == '\n');
  const std::string line = port.text.substr(0, port.text.size() - 1);

  const auto decoded = hmc::decode_board_frame(port.text, mode);
  REQUIRE(decoded.ok());
  CHECK(hmc::board_frame_id(*decoded) == spec.id);
  CHECK(hmc::is_event(*decoded) == (spec.name[0] == 'E'));
  const auto again = hmc::board_frame_values(*decoded);
  REQUIRE(again.ok());
  CHECK(std::vector<uint32_t>(again->values.begin(), again->values.begin() + again->count) == values);
  const auto encoded = hmc::encode_board_frame(*decoded, mode);
  REQUIRE(encoded.ok());
  CHECK(*encoded == line);
  CHECK_FALSE(hmc::describe(*decoded).empty());

  // The other mode's reader refuses the frame: a sum (1-3 digits) is not the CRC field's 5
  // digits; a CRC is out of range for the sum, or (at most 255) the wrong sum.
  const proto::ChecksumMode other =
      mode == proto::ChecksumMode::kSum ? proto::ChecksumMode::kCrc16 : proto::ChecksumMode::kSum;
  const auto crossed = hmc::decode_board_frame(line, other);
  if (mode == proto::ChecksumMode::kSum) {
    REQUIRE_FALSE(crossed.ok());
    CHECK(crossed.error().reason == proto::Reason::kBadNumber);
  } else if (!crossed.ok()) {
    CHECK((crossed.error().reason == proto::Reason::kChecksumMismatch ||
           crossed.error().reason == proto::Reason::kOutOfRange));
  }
}

}  // namespace

TEST_CASE("every board frame the firmware writes decodes to the values it was given") {
  std::mt19937 random(20240604);  // fixed: the same values on every run
  for (const proto::ChecksumMode mode : {proto::ChecksumMode::kSum, proto::ChecksumMode::kCrc16}) {
    for (const proto::BoardFrameSpec& spec : proto::kBoardFrames) {
      INFO(spec.name << (mode == proto::ChecksumMode::kCrc16 ? " (CRC-16)" : " (sum)"));
      check_round_trip(spec, values_for(spec, [](uint32_t min, uint32_t) { return min; }), mode);
      check_round_trip(spec, values_for(spec, [](uint32_t, uint32_t max) { return max; }), mode);
      for (int i = 0; i < 200; ++i) {
        check_round_trip(spec,
                         values_for(spec,
                                    [&random](uint32_t min, uint32_t max) {
                                      return std::uniform_int_distribution<uint32_t>(min, max)(random);
                                    }),
                         mode);
      }
    }
  }
}

TEST_CASE("the writer's ACK and NAK decode to typed replies") {
  CapturePort port;
  hmc::fw::write_nak(port, proto::Reason::kChecksumMismatch, 8, 24, proto::ChecksumMode::kCrc16);
  const auto nak = hmc::decode_board_frame(port.text, proto::ChecksumMode::kCrc16);
  REQUIRE(nak.ok());
  CHECK(std::get<hmc::Nak>(*nak) == hmc::Nak{proto::Reason::kChecksumMismatch, 8, 24});
  CHECK(hmc::describe(*nak) == "refused: checksum_mismatch at token 8, byte 24");

  port.text.clear();
  uint32_t values[4] = {3, proto::kEndStopped};
  hmc::fw::put_signed(values + 2, -1600);
  hmc::fw::write_frame(port, proto::BoardFrameId::kMotionEnded, values, proto::ChecksumMode::kSum);
  const auto ended = hmc::decode_board_frame(port.text);
  REQUIRE(ended.ok());
  CHECK(std::get<hmc::MotionEnded>(*ended) == hmc::MotionEnded{3, hmc::MotionEnd::kStopped, -1600});
  CHECK(hmc::describe(*ended) == "motor 3 stopped at -1600 (1/256 step)");
}
