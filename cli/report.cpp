// How `hmc` shows verdicts to people.
#include "report.h"

#include <string>

namespace hmc::cli {

void print_refusal(std::ostream& out, std::string_view line, const Diagnostic& d) {
  out << "error: " << proto::reason_spec(d.reason).name << ": " << d.message << "\n";
  if (line.empty() || d.offset > line.size()) return;
  // Show at most the line's limit, with control and non-ASCII bytes as '?', so the caret lines up.
  std::string shown;
  for (std::size_t i = 0; i < line.size() && i <= proto::kLineMax; ++i) {
    const auto c = static_cast<unsigned char>(line[i]);
    shown += (c >= 0x20 && c < 0x7F) ? static_cast<char>(c) : '?';
  }
  out << "  " << shown << (line.size() > shown.size() ? "..." : "") << "\n";
  out << "  " << std::string(d.offset, ' ') << "^ byte " << d.offset;
  if (!d.field.empty()) out << ", field '" << d.field << "'";
  out << "\n";
}

void print_warnings(std::ostream& out, const std::vector<Warning>& warnings) {
  for (const Warning& w : warnings) out << "warning: " << w.message << "\n";
}

void print_command(std::ostream& out, const Command& command, proto::ChecksumMode mode) {
  const proto::CommandSpec& spec = command_spec(command);
  const CommandValues v = command_values(command);
  out << spec.name << ": " << describe(command) << "\n ";
  for (uint32_t i = 0; i < v.count; ++i) out << " " << spec.fields[i].name << "=" << v.values[i];
  out << " checksum=" << checksum(command, mode) << "\n";
}

void print_board_frame(std::ostream& out, const BoardFrame& frame) {
  const proto::BoardFrameSpec& spec = board_frame_spec(frame);
  out << spec.name << (is_event(frame) ? " (event): " : " (reply): ") << describe(frame) << "\n";
  const auto values = board_frame_values(frame);  // a decoded frame always has its values
  if (!values || values->count == 0) return;
  out << " ";
  for (uint32_t i = 0; i < values->count; ++i) out << " " << spec.fields[i].name << "=" << values->values[i];
  out << "\n";
}

}  // namespace hmc::cli
