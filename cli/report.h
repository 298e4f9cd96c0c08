// How `hmc` shows verdicts to people: the frame, a caret under the byte at fault, the reason.
#pragma once

#include <ostream>
#include <string_view>

#include "hmc/board_frame.h"
#include "hmc/codec.h"

namespace hmc::cli {

// "error: <reason>: <message>", then the line with a caret at the offset and the field named.
void print_refusal(std::ostream& out, std::string_view line, const Diagnostic& d);
// "warning: <message>" for each warning.
void print_warnings(std::ostream& out, const std::vector<Warning>& warnings);
// "<NAME>: <description>" then "  field=value ... checksum=N" (the checksum in `mode`).
void print_command(std::ostream& out, const Command& command,
                   proto::ChecksumMode mode = proto::ChecksumMode::kSum);
// "<NAME> (reply|event): <description>" then "  field=value ..." as on the wire.
void print_board_frame(std::ostream& out, const BoardFrame& frame);

}  // namespace hmc::cli
