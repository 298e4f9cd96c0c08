// The board variant's name and its guessed pins, as text in the image (section .hmc_board_info,
// placed right after the vector table by samd21_sections.ld), so `hmc flash` can say which
// wiring an image expects before writing it, and what the board should answer to VER after:
// "hmc-board:seed;protocol:4;firmware:100;guessed:PA05,...;".
#include "board.h"
#include "core/protocol_facts.h"

namespace {

__attribute__((section(".hmc_board_info"), used)) constexpr hmc::samd21::pin_map::InfoText kBoardInfo =
    hmc::samd21::pin_map::info_text(hmc::samd21::board::kVariant, hmc::proto::kProtocolVersion,
                                    hmc::proto::kFirmwareVersion);
static_assert(kBoardInfo.text[sizeof(kBoardInfo.text) - 2] == '\0', "the board info text fits its 256 bytes");

}  // namespace
