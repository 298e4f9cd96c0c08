// Frames from the board to the host (protocol v2, docs/protocol.md "Replies" and "Protocol v2"):
// the reply to every line (ACK, NAK, or the answer to a query) and unprompted events (names
// starting with 'E'), typed.
//
// decode_board_frame() judges a line the board sent by the same order of checks as decode()
// (unknown name -> unknown_command, wrong length -> bad_length, checksum, then field ranges ->
// out_of_range) against proto::kBoardFrames, with the same Diagnostic. Signed positions arrive
// as a sign and a magnitude and are returned as one int64_t in 1/256 step.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>

#include "hmc/crc16.h"
#include "hmc/protocol_facts.h"
#include "hmc/codec.h"
#include "hmc/result.h"

namespace hmc {

// ACK: the line was accepted and carried out (a move: started).
struct Ack {
  bool operator==(const Ack&) const { return true; }
};

// NAK: the line was refused. `reason` may be a code this host does not know (a newer board).
struct Nak {
  proto::Reason reason = proto::Reason::kOk;
  uint32_t token = 0;   // proto::kNoToken (255): none, for line_too_long
  uint32_t offset = 0;  // byte offset in the refused line
  bool operator==(const Nak& o) const { return reason == o.reason && token == o.token && offset == o.offset; }
};

// VER: the answer to VER.
struct Version {
  uint32_t protocol = 0;
  uint32_t firmware = 0;  // major*10000 + minor*100 + patch
  bool legacy = false;    // seed rule [5] in force
  uint32_t line_max = 0;
  uint32_t max_rate = 0;  // step-rate budget of the moving motors together, steps/s
  uint32_t board = 0;     // motors*100 + servos*10 + strips
  uint32_t switch_mask = 0;  // bit m-1: motor m has limit switches
  proto::ChecksumMode checksum_mode = proto::ChecksumMode::kSum;
  // The budget while any moving motor ramps: protocol 7 (proto::Feature::kStepBudgets) on;
  // nothing from an older board, whose VER has 8 values.
  std::optional<uint32_t> max_ramping_rate;
  bool operator==(const Version& o) const {
    return protocol == o.protocol && firmware == o.firmware && legacy == o.legacy && line_max == o.line_max &&
           max_rate == o.max_rate && board == o.board && switch_mask == o.switch_mask &&
           checksum_mode == o.checksum_mode && max_ramping_rate == o.max_ramping_rate;
  }
};

// The step interrupt's budgets, summed over the moving motors (VER's max_rate and
// max_ramping_rate); by default this firmware's own.
struct StepBudgets {
  uint32_t constant = proto::kMaxStepRate;
  uint32_t ramping = proto::kMaxRampingStepRate;  // while any moving motor ramps
  uint32_t when(bool any_ramps) const { return any_ramps ? ramping : constant; }
  bool operator==(const StepBudgets& o) const { return constant == o.constant && ramping == o.ramping; }
};

enum class MotorState : uint8_t { kIdle, kMoving, kHoming, kChanging, kSelfTest };

// STA (units 1-3): one motor.
struct MotorStatus {
  uint32_t motor = 1;
  MotorState state = MotorState::kIdle;
  int64_t position = 0;  // 1/256 step
  int64_t target = 0;    // where the move ends (the position when it runs until stopped)
  uint32_t rate = 0;     // steps/s now
  bool homed = false;
  uint32_t switches = 0;  // bit e: the switch at end e is pressed
  bool endless = false;   // runs until stopped
  uint32_t microstep = 1; // 1 << (flags bits 4-7)
  bool operator==(const MotorStatus& o) const {
    return motor == o.motor && state == o.state && position == o.position && target == o.target &&
           rate == o.rate && homed == o.homed && switches == o.switches && endless == o.endless &&
           microstep == o.microstep;
  }
};

// STB (unit 4): the board's switches and servos.
struct BoardStatus {
  bool emergency = false;
  uint32_t limits = 0;     // bit 2(m-1)+end: that limit switch is pressed
  uint32_t servo1_us = 0;  // pulse, 0 released
  uint32_t servo2_us = 0;
  bool limit_pressed(uint32_t motor, uint32_t end) const { return ((limits >> (2 * (motor - 1) + end)) & 1u) != 0; }
  bool operator==(const BoardStatus& o) const {
    return emergency == o.emergency && limits == o.limits && servo1_us == o.servo1_us && servo2_us == o.servo2_us;
  }
};

// STL (units 5-6): one LED strip's colour.
struct StripStatus {
  uint32_t strip = 1;
  uint32_t r = 0, g = 0, b = 0, w = 0;
  bool operator==(const StripStatus& o) const {
    return strip == o.strip && r == o.r && g == o.g && b == o.b && w == o.w;
  }
};

// SET: the answer to GET.
struct SettingValue {
  uint32_t motor = 1;
  uint32_t setting = proto::kSettingCurrent;
  uint32_t value = 0;
  bool operator==(const SettingValue& o) const { return motor == o.motor && setting == o.setting && value == o.value; }
};

// EVB: the board booted (its checksum mode is the seed's sum again).
struct Booted {
  uint32_t protocol = 0;
  uint32_t firmware = 0;
  bool operator==(const Booted& o) const { return protocol == o.protocol && firmware == o.firmware; }
};

// How a motion ended (EVD): the values are proto::kEnd*.
enum class MotionEnd : uint8_t { kCompleted = 1, kStopped, kLimit, kEmergency, kDropped, kWatchdog };

// EVD: a motion ended.
struct MotionEnded {
  uint32_t motor = 1;
  MotionEnd how = MotionEnd::kCompleted;
  int64_t position = 0;
  bool operator==(const MotionEnded& o) const { return motor == o.motor && how == o.how && position == o.position; }
};

// EVH: homing ended.
struct HomingEnded {
  uint32_t motor = 1;
  bool homed = false;  // false: the switch was not found
  int64_t position = 0;
  bool operator==(const HomingEnded& o) const { return motor == o.motor && homed == o.homed && position == o.position; }
};

// EVL: a limit switch changed.
struct LimitChanged {
  uint32_t motor = 1;
  uint32_t end = 0;  // 0 toward reverse, 1 toward forward
  bool pressed = false;
  bool operator==(const LimitChanged& o) const { return motor == o.motor && end == o.end && pressed == o.pressed; }
};

// EVE: the emergency switch changed.
struct EmergencyChanged {
  bool pressed = false;
  bool operator==(const EmergencyChanged& o) const { return pressed == o.pressed; }
};

// EVF: a driver fault appeared; `status` is the DRV8711 STATUS register's bits.
struct DriverFault {
  uint32_t motor = 1;
  uint32_t status = 0;
  bool operator==(const DriverFault& o) const { return motor == o.motor && status == o.status; }
};

// STW (STA 7, protocol 3): the link watchdog.
struct WatchdogStatus {
  uint32_t timeout_ms = 0;  // armed with this timeout; 0 off
  bool fired = false;       // it braked the motors since it was last armed
  bool operator==(const WatchdogStatus& o) const { return timeout_ms == o.timeout_ms && fired == o.fired; }
};

// Why the board last reset and, after a fault, where (protocol 4, proto::kResetFields).
struct ResetInfo {
  proto::ResetCause cause = proto::ResetCause::kUnknown;
  uint32_t exception = 0;  // fault: the exception that caught it (3 HardFault, 16 + n interrupt n)
  uint32_t pc = 0;         // fault: the faulting instruction's address
  uint32_t lr = 0;         // fault: the link register, bit 31 dropped (0x7FFFFFFx: an exception return)
  uint32_t context = 0;    // fault: 0 the main loop, else the exception number that ran
  bool operator==(const ResetInfo& o) const {
    return cause == o.cause && exception == o.exception && pc == o.pc && lr == o.lr && context == o.context;
  }
};
// STR: the answer to STA 8.
struct ResetStatus : ResetInfo {};
// EVR (protocol 4): sent right after EVB at boot.
struct ResetEvent : ResetInfo {};

// Ordered by proto::BoardFrameId.
using BoardFrame = std::variant<Ack, Nak, Version, MotorStatus, BoardStatus, StripStatus, SettingValue, Booted,
                                MotionEnded, HomingEnded, LimitChanged, EmergencyChanged, DriverFault,
                                WatchdogStatus, ResetStatus, ResetEvent>;

proto::BoardFrameId board_frame_id(const BoardFrame& frame);
const proto::BoardFrameSpec& board_frame_spec(const BoardFrame& frame);
// True for events (sent unprompted), false for replies.
bool is_event(const BoardFrame& frame);

// Judges one line the board sent. One trailing LF, CRLF or CR is allowed and removed.
Result<BoardFrame, Diagnostic> decode_board_frame(std::string_view line,
                                                  proto::ChecksumMode mode = proto::ChecksumMode::kSum);

// The frame's values in wire order (signed positions as sign and magnitude). Refuses, as
// out_of_range, what the wire cannot carry: a magnitude above INT_MAX, a microstep that is not a
// power of two up to 2^15, a field outside its range.
Result<CommandValues, Diagnostic> board_frame_values(const BoardFrame& frame);

// The canonical frame, without a line end, as the board writes it.
Result<std::string, Diagnostic> encode_board_frame(const BoardFrame& frame,
                                                   proto::ChecksumMode mode = proto::ChecksumMode::kSum);

// In words: "motor 1 stopped at -1600 (1/256 step)", "refused: checksum_mismatch at token 8, byte 24".
std::string describe(const BoardFrame& frame);

// Names used in words and JSON: "idle", "moving", ...; "completed", "stopped", ...
const char* motor_state_name(MotorState state);
const char* motion_end_name(MotionEnd how);
// "power_on", ..., "fault"; "unknown" for a code this host does not know.
const char* reset_cause_name(proto::ResetCause cause);
// "power-on", "a fault (HardFault) at pc 0x000021A0, lr 0x00002311, in the main loop", ...
std::string reset_text(const ResetInfo& reset);
// "0.1.0" from major*10000 + minor*100 + patch.
std::string firmware_version_text(uint32_t firmware);

}  // namespace hmc
