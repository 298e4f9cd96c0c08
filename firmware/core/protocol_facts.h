// The protocol's facts, written once: frame limits, command names, fields, value ranges,
// the spec's advised ranges, board facts the grammar depends on, and the refusal reasons.
//
// Read by the firmware's FrameParser, the host codec, the docs test and the conformance
// runner. Each of those applies these facts with its own algorithm; nothing here parses.
// Freestanding: no heap, no library beyond <stdint.h>.
#pragma once

#include <stdint.h>

namespace hmc::proto {

// ---------------------------------------------------------------------------------------
// Frame limits (docs/protocol.md, "Lines" and "Numbers")

// Largest number a field may hold: the spec's INT_MAX.
inline constexpr uint32_t kIntMax = 2147483647u;
// Most digits a number may have (leading zeros count).
inline constexpr uint32_t kMaxDigits = 10;
// Most bytes on one line, its terminator excluded. The longest frame the grammar allows for a
// command of kMaxCommandValues values, every number written with kMaxDigits digits, is
// 4 (STX#) + 11 (len#) + 4 (name#) + 6 * 11 (values#, checksum#) + 3 (ETX) = 88 bytes; the
// board's longest reply (VER) is shorter, its fields' ranges bounding their digits.
// 128 holds that with room for surrounding blanks and is one power of two of RAM.
inline constexpr uint32_t kLineMax = 128;
// Most values after the name any command has (STM and LIM have 5), and any frame (VER has 9).
inline constexpr uint32_t kMaxCommandValues = 5;
inline constexpr uint32_t kMaxValues = 9;
// The checksum field's largest value.
inline constexpr uint32_t kChecksumMax = 255;
// In CRC-16 mode (docs/protocol.md "CRC-16 mode") the checksum field holds 0..kCrcMax.
inline constexpr uint32_t kCrcMax = 65535;
// In CRC-16 mode the checksum field is always exactly this many digits, zero-padded.
inline constexpr uint32_t kCrcDigits = 5;
// Token positions that do not depend on the command.
inline constexpr uint8_t kTokenStart = 0;
inline constexpr uint8_t kTokenLength = 1;
inline constexpr uint8_t kTokenName = 2;
inline constexpr uint8_t kTokenFirstValue = 3;
// Marks "no token" in a verdict (line too long).
inline constexpr uint8_t kNoToken = 0xFF;

// ---------------------------------------------------------------------------------------
// Refusal reasons. Numbers are stable: they are the reply codes of protocol v2.

enum class Reason : uint8_t {
  kOk = 0,
  kLineTooLong = 1,       // more than kLineMax bytes before the line end
  kBadByte = 2,           // a byte outside '!'..'~' inside the frame
  kBadStart = 3,          // the frame does not begin with the token STX
  kBadEnd = 4,            // the frame does not end with the token ETX
  kBadLength = 5,         // the length field disagrees with the fields present or the command
  kBadNumber = 6,         // a numeric field is not 1-10 decimal digits up to kIntMax
  kUnknownCommand = 7,    // the name is not in the command table
  kChecksumMismatch = 8,  // the checksum field is not the sum of the values mod 256
  kOutOfRange = 9,        // a value is outside its field's range
  kNoSwitch = 10,         // homing asked of a motor that has no limit switch
  // Refusals by the board's rules (controller.h), after the frame itself was accepted.
  kLimitPressed = 11,     // a move toward a limit switch that is pressed (seed rule [1])
  kMotorsRunning = 12,    // homing while a motor moves (seed rule [2])
  kEmergencyStop = 13,    // motion while the emergency switch is pressed
  kBusy = 14,             // legacy mode: servo or LED while a stepper runs (seed rule [5])
  kRateLimit = 15,        // the step rate is beyond what the board can time
  kSoftLimit = 16,        // the move would end outside the motor's soft travel limits
};

struct ReasonSpec {
  Reason reason;
  const char* name;  // stable identifier used in vectors, JSON output and docs
  const char* text;  // what it means, for people
};

inline constexpr ReasonSpec kReasons[] = {
    {Reason::kOk, "ok", "accepted"},
    {Reason::kLineTooLong, "line_too_long", "line is longer than 128 bytes"},
    {Reason::kBadByte, "bad_byte", "byte that cannot appear inside a frame"},
    {Reason::kBadStart, "bad_start", "frame does not start with STX"},
    {Reason::kBadEnd, "bad_end", "frame does not end with ETX"},
    {Reason::kBadLength, "bad_length", "length field does not match the fields"},
    {Reason::kBadNumber, "bad_number", "field is not an unsigned decimal number"},
    {Reason::kUnknownCommand, "unknown_command", "unknown command name"},
    {Reason::kChecksumMismatch, "checksum_mismatch", "checksum does not match the values"},
    {Reason::kOutOfRange, "out_of_range", "value outside the field's range"},
    {Reason::kNoSwitch, "no_switch", "motor has no limit switch to home against"},
    {Reason::kLimitPressed, "limit_pressed", "move toward a pressed limit switch"},
    {Reason::kMotorsRunning, "motors_running", "homing needs every motor at rest"},
    {Reason::kEmergencyStop, "emergency_stop", "emergency switch is pressed"},
    {Reason::kBusy, "busy", "servo and LED wait while a stepper runs (legacy mode)"},
    {Reason::kRateLimit, "rate_limit", "step rate beyond what the board can time"},
    {Reason::kSoftLimit, "soft_limit", "move would leave the soft travel limits"},
};
inline constexpr uint32_t kReasonCount = sizeof(kReasons) / sizeof(kReasons[0]);

// The entry for a reason; reasons are numbered densely from 0, so this is an index.
constexpr const ReasonSpec& reason_spec(Reason r) { return kReasons[static_cast<uint8_t>(r)]; }

constexpr bool reasons_indexed_by_code() {
  for (uint32_t i = 0; i < kReasonCount; ++i) {
    if (static_cast<uint32_t>(kReasons[i].reason) != i) return false;
  }
  return true;
}
static_assert(reasons_indexed_by_code(), "kReasons[i] must describe reason code i");

// ---------------------------------------------------------------------------------------
// Board facts the grammar depends on

inline constexpr uint32_t kMotorCount = 3;
inline constexpr uint32_t kServoCount = 2;
inline constexpr uint32_t kStripCount = 2;
// Motors 1 and 2 each have two limit switches; motor 3 has none (seed 003, 개요; DESIGN).
constexpr bool motor_has_switches(uint32_t motor) { return motor == 1 || motor == 2; }
// Servo pulse for an angle: 544 + angle·1856/180 µs, rounded (HARDWARE.md, Servos).
constexpr uint16_t servo_pulse_us(uint32_t angle) {
  return static_cast<uint16_t>(544u + (angle * 1856u + 90u) / 180u);
}

// STM's action field (its second value).
inline constexpr uint32_t kActionStop = 0;
inline constexpr uint32_t kActionForward = 1;
inline constexpr uint32_t kActionReverse = 2;
inline constexpr uint32_t kActionHome = 3;

// ---------------------------------------------------------------------------------------
// Commands and their fields

enum class CommandId : uint8_t {
  kStepper,
  kServo,
  kLed,
  // Protocol v2 (docs/protocol.md "Protocol v2").
  kVersion,       // VER: version and capabilities query
  kStatus,        // STA: status query of one unit
  kSet,           // SET: change a motor setting
  kGet,           // GET: read a motor setting
  kLimits,        // LIM: soft travel limits
  kChecksumMode,  // CRC: the seed's sum or CRC-16
  // Protocol 3.
  kWatchdog,      // WDG: the link watchdog
  // Protocol 6.
  kSetPosition,   // POS: set a resting motor's position (protocol 6)
};

enum FieldFlag : uint8_t {
  kPowerOfTwo = 1u << 0,        // the value must be a power of two (0 is not one)
  kUncheckedOnStop = 1u << 1,   // not checked at all when the action is stop
  kZeroAllowedOnHome = 1u << 2, // 0 is also accepted when the action is home
  kSettingValue = 1u << 3,      // range given by the setting the previous field names
};

struct FieldSpec {
  const char* name;      // identifier in JSON, vectors and messages
  uint32_t min;          // smallest accepted value
  uint32_t max;          // largest accepted value
  uint8_t flags;         // FieldFlag bits
  uint32_t advised_min;  // the spec's table advises [advised_min, advised_max]; the host
  uint32_t advised_max;  // warns outside it (both 0: no advice)
  const char* meaning;   // one line for help and docs
};

struct CommandSpec {
  const char* name;        // case-sensitive wire name
  CommandId id;
  uint8_t value_count;     // values after the name; the length field is value_count + 1
  const FieldSpec* fields; // value_count entries
  int8_t action_field;     // index of the stop/move/home field, or -1
  const char* summary;
};

inline constexpr FieldSpec kStepperFields[] = {
    {"motor", 1, kMotorCount, 0, 0, 0, "stepper 1-3"},
    {"dir", 0, 3, 0, 0, 0, "0 stop, 1 forward, 2 reverse, 3 home"},
    {"microstep", 1, 256, kPowerOfTwo | kUncheckedOnStop | kZeroAllowedOnHome, 0, 0,
     "1, 2, 4 ... 256 microsteps per full step (0 when homing: keep the current one)"},
    {"steps", 0, kIntMax, kUncheckedOnStop, 0, 0,
     "steps to move, 0 = until stopped (homing: most steps to seek, 0 = no bound)"},
    {"delay_us", 1, kIntMax, kUncheckedOnStop | kZeroAllowedOnHome, 100, 3000,
     "microseconds per step (0 when homing: the default homing rate)"},
};
inline constexpr FieldSpec kServoFields[] = {
    {"servo", 1, kServoCount, 0, 0, 0, "servo 1 (pan) or 2 (tilt)"},
    {"angle", 10, 170, 0, 0, 0, "degrees, 90 is centre"},
};
inline constexpr FieldSpec kLedFields[] = {
    {"strip", 1, kStripCount, 0, 0, 0, "LED strip 1 or 2"},
    {"r", 0, 255, 0, 0, 0, "red"},
    {"g", 0, 255, 0, 0, 0, "green"},
    {"b", 0, 255, 0, 0, 0, "blue"},
    {"w", 0, 255, 0, 0, 0, "white"},
};

// Motor settings (SET / GET), numbered from 1; defaults reproduce the seed.
struct SettingSpec {
  const char* name;
  uint32_t min;
  uint32_t max;
  uint32_t initial;
  const char* meaning;
};
inline constexpr SettingSpec kSettings[] = {
    {"current_ma", 100, 4000, 1000, "full-scale coil current, mA"},
    {"decay", 0, 5, 5, "DRV8711 decay mode (5 auto-mixed)"},
    {"accel", 0, 2000000, 0, "steps/s^2; 0 constant rate"},
    {"max_rate", 1, 50000, 50000, "fastest accepted move, steps/s"},
    {"home_end", 0, 1, 0, "switch end homing seeks (0 toward reverse)"},
    {"home_seek_us", 5, 1000000, 500, "delay per step seeking, when the frame's is 0"},
    {"home_pull_off", 0, 100000, 0, "steps back off the switch after it closes"},
    {"home_locate_us", 0, 1000000, 0, "delay per step re-approaching slowly (0: none)"},
};
inline constexpr uint32_t kSettingCount = sizeof(kSettings) / sizeof(kSettings[0]);
enum SettingId : uint8_t {
  kSettingCurrent = 1,
  kSettingDecay,
  kSettingAccel,
  kSettingMaxRate,
  kSettingHomeEnd,
  kSettingHomeSeek,
  kSettingHomePullOff,
  kSettingHomeLocate,
};
static_assert(kSettingHomeLocate == kSettingCount, "one SettingId per kSettings entry");

// Step rates our firmware can time (controller_motion.cpp applies them; the host names the one a
// `rate_limit` refusal broke, with these numbers). A move's rate is 1 000 000 / delay_us steps/s,
// rounded up; it must also stay within the motor's max_rate setting.
// The step budget, summed over the moving motors, from the real image's cycles in hmc-emu's
// cycle model (docs/performance.md, "Cycles on the real image"; scripts/bench cycles). The rule:
// the step interrupt uses at most half the 48 MHz CPU at the budget (24 000 000 cycles a second).
// One compare timer per motor and an express entry (step_engine.h):
//  - Constant rate: 129-138 cycles a step (three at the spec's 20 us: 129, 40.4 % of the CPU;
//    one motor, or three on their own grids: 138). 150 000 takes the spec's 20 us move on every
//    motor at once (at 138 cycles a step, 43 % of the CPU).
//  - Ramping: 149-153 cycles a ramping step (one motor; three ramping toward 76 us; three
//    toward 20 us at 50 000 steps/s²): at 150 000 at most 48 % of the CPU. The main loop keeps
//    the rings full meanwhile (three motors ramping to 20 us: every interval monotone, none
//    dry).
// VER reports both (max_rate, max_ramping_rate).
inline constexpr uint32_t kMaxStepRate = 150000;
inline constexpr uint32_t kMaxRampingStepRate = 150000;  // when any moving motor ramps
// The step timer's shortest and longest interval at 48 ticks a µs: 240 ticks, 2^32 - 1 ticks.
inline constexpr uint32_t kShortestDelayUs = 5;
inline constexpr uint32_t kLongestDelayUs = 89478485;
constexpr bool delay_in_range(uint32_t delay_us) {
  return delay_us >= kShortestDelayUs && delay_us <= kLongestDelayUs;
}
constexpr uint32_t step_rate(uint32_t delay_us) { return (1000000u + delay_us - 1u) / delay_us; }
constexpr uint32_t step_budget(bool ramping) { return ramping ? kMaxRampingStepRate : kMaxStepRate; }

// STA's units.
inline constexpr uint32_t kUnitBoard = 4;        // switches, emergency, servos
inline constexpr uint32_t kUnitFirstStrip = 5;   // 5 and 6: LED strips 1 and 2
inline constexpr uint32_t kUnitWatchdog = kUnitFirstStrip + kStripCount;  // 7, protocol 3
inline constexpr uint32_t kUnitReset = kUnitWatchdog + 1;                  // 8: why the board last reset, protocol 4
// The units every protocol-2 board answers; the later ones came with a feature (kFeatures'
// status_unit), and a board older than the feature refuses its unit as out of range.
inline constexpr uint32_t kUnitLastBase = kUnitFirstStrip + kStripCount - 1;  // 6

inline constexpr FieldSpec kStatusFields[] = {
    {"unit", 1, kUnitReset, 0, 0, 0,
     "1-3 a motor, 4 the board, 5-6 LED strip 1-2, 7 the link watchdog (protocol 3), 8 the last reset (protocol 4)"},
};
inline constexpr FieldSpec kSetFields[] = {
    {"motor", 1, kMotorCount, 0, 0, 0, "stepper 1-3"},
    {"setting", 1, kSettingCount, 0, 0, 0, "setting id (docs/protocol.md, Settings)"},
    {"value", 0, kIntMax, kSettingValue, 0, 0, "new value, within the setting's range"},
};
inline constexpr FieldSpec kGetFields[] = {
    {"motor", 1, kMotorCount, 0, 0, 0, "stepper 1-3"},
    {"setting", 1, kSettingCount, 0, 0, 0, "setting id (docs/protocol.md, Settings)"},
};
inline constexpr FieldSpec kLimitFields[] = {
    {"motor", 1, kMotorCount, 0, 0, 0, "stepper 1-3"},
    {"low_sign", 0, 1, 0, 0, 0, "0 plus, 1 minus"},
    {"low", 0, kIntMax, 0, 0, 0, "lowest position, 1/256 step"},
    {"high_sign", 0, 1, 0, 0, 0, "0 plus, 1 minus"},
    {"high", 0, kIntMax, 0, 0, 0, "highest position, 1/256 step (low < high enables)"},
};
inline constexpr FieldSpec kChecksumModeFields[] = {
    {"mode", 0, 1, 0, 0, 0, "0 the seed's sum, 1 CRC-16"},
};
// The link watchdog (docs/protocol.md "Link watchdog"): with a timeout set, the board brakes
// every motor when no line has ended for that long. A minute bounds how long a lost host's
// motors may run on.
inline constexpr uint32_t kWatchdogMaxMs = 60000;
inline constexpr FieldSpec kWatchdogFields[] = {
    {"timeout_ms", 0, kWatchdogMaxMs, 0, 0, 0, "brake every motor after this long without a line; 0 off"},
};

inline constexpr FieldSpec kPositionFields[] = {
    {"motor", 1, kMotorCount, 0, 0, 0, "stepper 1-3"},
    {"sign", 0, 1, 0, 0, 0, "0 plus, 1 minus"},
    {"position", 0, kIntMax, 0, 0, 0, "the motor's position from now on, 1/256 step"},
};

inline constexpr CommandSpec kCommands[] = {
    {"STM", CommandId::kStepper, 5, kStepperFields, 1, "stepper: move, run, stop or home"},
    {"SVM", CommandId::kServo, 2, kServoFields, -1, "servo: go to an angle"},
    {"LED", CommandId::kLed, 5, kLedFields, -1, "LED strip: set one colour"},
    {"VER", CommandId::kVersion, 0, nullptr, -1, "query: version and capabilities"},
    {"STA", CommandId::kStatus, 1, kStatusFields, -1, "query: status of a motor, the board or a strip"},
    {"SET", CommandId::kSet, 3, kSetFields, -1, "change a motor setting"},
    {"GET", CommandId::kGet, 2, kGetFields, -1, "query: a motor setting"},
    {"LIM", CommandId::kLimits, 5, kLimitFields, -1, "soft travel limits of a motor"},
    {"CRC", CommandId::kChecksumMode, 1, kChecksumModeFields, -1, "checksum mode: sum or CRC-16"},
    {"WDG", CommandId::kWatchdog, 1, kWatchdogFields, -1, "link watchdog: arm with a timeout, 0 disarms"},
    {"POS", CommandId::kSetPosition, 3, kPositionFields, -1, "set a resting motor's position (zero it)"},
};
inline constexpr uint32_t kCommandCount = sizeof(kCommands) / sizeof(kCommands[0]);

// The entry for a command id; kCommands is ordered by CommandId.
constexpr const CommandSpec& command_spec(CommandId id) { return kCommands[static_cast<uint8_t>(id)]; }

constexpr bool commands_indexed_by_id() {
  for (uint32_t i = 0; i < kCommandCount; ++i) {
    if (static_cast<uint32_t>(kCommands[i].id) != i) return false;
  }
  return true;
}
static_assert(commands_indexed_by_id(), "kCommands[i] must describe CommandId i");

// ---------------------------------------------------------------------------------------
// Board -> host frames (protocol v2, docs/protocol.md "Replies" and "Protocol v2"). One reply
// per non-blank line received; events (names starting with 'E') come unprompted between them.

inline constexpr uint32_t kProtocolVersion = 7;
inline constexpr uint32_t kFirmwareVersion = 100;  // major·10000 + minor·100 + patch: 0.1.0

// Why the board last reset (EVR, STR). The SAMD21 reads it from PM RCAUSE; kFault is a system
// reset its fault handler requested after recording where the fault happened.
enum class ResetCause : uint8_t {
  kUnknown = 0,   // no cause recorded (e.g. a board that cannot tell)
  kPowerOn = 1,
  kBrownOut = 2,  // supply dipped below the brown-out detector's level
  kExternal = 3,  // the reset pin
  kWatchdog = 4,  // the main loop stopped kicking the watchdog
  kSoftware = 5,  // a system reset request (a bootloader, bossac -R, the firmware itself)
  kFault = 6,     // a CPU fault or an interrupt without a handler: exception, pc, lr say where
};
inline constexpr const char* kResetCauseNames[] = {"unknown",  "power_on", "brown_out", "external",
                                                   "watchdog", "software", "fault"};
inline constexpr uint32_t kResetCauseCount = sizeof(kResetCauseNames) / sizeof(kResetCauseNames[0]);
// Exception numbers (ARMv6-M): 2 NMI, 3 HardFault, 16 + n peripheral interrupt n (SAMD21: 28).
inline constexpr uint32_t kMaxException = 16 + 28 - 1;

enum class BoardFrameId : uint8_t {
  kAck,
  kNak,
  kVersion,
  kMotorStatus,
  kBoardStatus,
  kStripStatus,
  kSettingValue,
  kBooted,
  kMotionEnded,
  kHomingEnded,
  kLimitChanged,
  kEmergencyChanged,
  kDriverFault,
  kWatchdogStatus,  // protocol 3
  kResetStatus,     // protocol 4
  kResetEvent,      // protocol 4
};

struct BoardFrameSpec {
  const char* name;
  BoardFrameId id;
  uint8_t value_count;
  const FieldSpec* fields;
  const char* summary;
};

// How a motion ended (EVD).
inline constexpr uint32_t kEndCompleted = 1;
inline constexpr uint32_t kEndStopped = 2;
inline constexpr uint32_t kEndLimit = 3;
inline constexpr uint32_t kEndEmergency = 4;
inline constexpr uint32_t kEndDropped = 5;
inline constexpr uint32_t kEndWatchdog = 6;  // protocol 3: braked by the link watchdog

inline constexpr FieldSpec kNakFields[] = {
    {"reason", 1, 255, 0, 0, 0, "reason code"},
    {"token", 0, 255, 0, 0, 0, "token index (255: none)"},
    {"offset", 0, kLineMax, 0, 0, 0, "byte offset in the line"},
};
inline constexpr FieldSpec kVersionFields[] = {
    {"protocol", 1, 255, 0, 0, 0, "protocol version"},
    {"firmware", 0, kIntMax, 0, 0, 0, "major*10000 + minor*100 + patch"},
    {"legacy", 0, 1, 0, 0, 0, "1: seed rule [5] in force"},
    {"line_max", 1, 65535, 0, 0, 0, "longest line the board reads"},
    {"max_rate", 1, kIntMax, 0, 0, 0, "step-rate budget of the moving motors together, steps/s"},
    {"board", 0, 999, 0, 0, 0, "motors*100 + servos*10 + strips"},
    {"switch_mask", 0, 7, 0, 0, 0, "bit m-1: motor m has limit switches"},
    {"checksum_mode", 0, 1, 0, 0, 0, "0 sum, 1 CRC-16"},
    {"max_ramping_rate", 1, kIntMax, 0, 0, 0, "the same while any moving motor ramps, steps/s (protocol 7)"},
};
// A board older than protocol 7 (Feature::kStepBudgets) sends VER without max_ramping_rate.
inline constexpr uint8_t kVersionValuesBefore7 = 8;
inline constexpr FieldSpec kMotorStatusFields[] = {
    {"motor", 1, kMotorCount, 0, 0, 0, "stepper 1-3"},
    {"state", 0, 4, 0, 0, 0, "0 idle, 1 moving, 2 homing, 3 changing, 4 self-test"},
    {"pos_sign", 0, 1, 0, 0, 0, "0 plus, 1 minus"},
    {"pos", 0, kIntMax, 0, 0, 0, "position, 1/256 step"},
    {"target_sign", 0, 1, 0, 0, 0, "0 plus, 1 minus"},
    {"target", 0, kIntMax, 0, 0, 0, "where the move ends, 1/256 step"},
    {"rate", 0, kIntMax, 0, 0, 0, "steps/s now"},
    {"flags", 0, 255, 0, 0, 0, "bit 0 homed, 1 switch end 0, 2 end 1, 3 runs until stopped, 4-7 log2 microstep"},
};
inline constexpr FieldSpec kBoardStatusFields[] = {
    {"emergency", 0, 1, 0, 0, 0, "1: emergency switch pressed"},
    {"limits", 0, 15, 0, 0, 0, "bit 2(m-1)+end: that limit switch is pressed"},
    {"servo1_us", 0, 2400, 0, 0, 0, "servo 1 pulse, 0 released"},
    {"servo2_us", 0, 2400, 0, 0, 0, "servo 2 pulse, 0 released"},
};
inline constexpr FieldSpec kMotionEndedFields[] = {
    {"motor", 1, kMotorCount, 0, 0, 0, "stepper 1-3"},
    {"how", kEndCompleted, kEndWatchdog, 0, 0, 0,
     "1 completed, 2 stopped, 3 limit switch, 4 emergency, 5 dropped, 6 link watchdog"},
    {"pos_sign", 0, 1, 0, 0, 0, "0 plus, 1 minus"},
    {"pos", 0, kIntMax, 0, 0, 0, "position, 1/256 step"},
};
inline constexpr FieldSpec kHomingEndedFields[] = {
    {"motor", 1, kMotorCount, 0, 0, 0, "stepper 1-3"},
    {"homed", 0, 1, 0, 0, 0, "1 homed (position 0), 0 switch not found"},
    {"pos_sign", 0, 1, 0, 0, 0, "0 plus, 1 minus"},
    {"pos", 0, kIntMax, 0, 0, 0, "position, 1/256 step"},
};
inline constexpr FieldSpec kBootedFields[] = {
    {"protocol", 1, 255, 0, 0, 0, "protocol version"},
    {"firmware", 0, kIntMax, 0, 0, 0, "major*10000 + minor*100 + patch"},
};
// EVR (after EVB at boot) and STR (the answer to STA 8): why the board last reset. The fault
// fields are 0 unless cause is fault. Addresses travel as decimal numbers up to INT_MAX: `lr`
// drops bit 31, which only the exception-return values 0xFFFFFFF1/9/D have on this chip.
inline constexpr FieldSpec kResetFields[] = {
    {"cause", 0, kResetCauseCount - 1, 0, 0, 0,
     "0 unknown, 1 power-on, 2 brown-out, 3 reset pin, 4 watchdog, 5 software, 6 fault"},
    {"exception", 0, kMaxException, 0, 0, 0, "fault: the exception that caught it (3 HardFault, 16+n interrupt n)"},
    {"pc", 0, kIntMax, 0, 0, 0, "fault: the address of the faulting instruction"},
    {"lr", 0, kIntMax, 0, 0, 0, "fault: the link register then (bit 31 dropped)"},
    {"context", 0, kMaxException, 0, 0, 0, "fault: what ran then (0 the main loop, else its exception number)"},
};

inline constexpr FieldSpec kLimitChangedFields[] = {
    {"motor", 1, kMotorCount, 0, 0, 0, "motor with switches"},
    {"end", 0, 1, 0, 0, 0, "0 toward reverse, 1 toward forward"},
    {"pressed", 0, 1, 0, 0, 0, "1 pressed, 0 released"},
};
inline constexpr FieldSpec kEmergencyChangedFields[] = {
    {"pressed", 0, 1, 0, 0, 0, "1 pressed, 0 released"},
};
inline constexpr FieldSpec kWatchdogStatusFields[] = {
    {"timeout_ms", 0, kWatchdogMaxMs, 0, 0, 0, "armed with this timeout; 0 off"},
    {"fired", 0, 1, 0, 0, 0, "1: it braked the motors since it was last armed"},
};
inline constexpr FieldSpec kDriverFaultFields[] = {
    {"motor", 1, kMotorCount, 0, 0, 0, "stepper 1-3"},
    {"status", 0, 255, 0, 0, 0, "DRV8711 STATUS bits"},
};

inline constexpr BoardFrameSpec kBoardFrames[] = {
    {"ACK", BoardFrameId::kAck, 0, nullptr, "reply: the line was accepted"},
    {"NAK", BoardFrameId::kNak, 3, kNakFields, "reply: the line was refused"},
    {"VER", BoardFrameId::kVersion, 9, kVersionFields, "reply to VER (8 values before protocol 7)"},
    {"STA", BoardFrameId::kMotorStatus, 8, kMotorStatusFields, "reply to STA 1-3"},
    {"STB", BoardFrameId::kBoardStatus, 4, kBoardStatusFields, "reply to STA 4"},
    {"STL", BoardFrameId::kStripStatus, 5, kLedFields, "reply to STA 5-6"},
    {"SET", BoardFrameId::kSettingValue, 3, kSetFields, "reply to GET"},
    {"EVB", BoardFrameId::kBooted, 2, kBootedFields, "event: the board booted"},
    {"EVD", BoardFrameId::kMotionEnded, 4, kMotionEndedFields, "event: a motion ended"},
    {"EVH", BoardFrameId::kHomingEnded, 4, kHomingEndedFields, "event: homing ended"},
    {"EVL", BoardFrameId::kLimitChanged, 3, kLimitChangedFields, "event: a limit switch changed"},
    {"EVE", BoardFrameId::kEmergencyChanged, 1, kEmergencyChangedFields, "event: the emergency switch changed"},
    {"EVF", BoardFrameId::kDriverFault, 2, kDriverFaultFields, "event: a driver fault"},
    {"STW", BoardFrameId::kWatchdogStatus, 2, kWatchdogStatusFields, "reply to STA 7 (protocol 3)"},
    {"STR", BoardFrameId::kResetStatus, 5, kResetFields, "reply to STA 8 (protocol 4)"},
    {"EVR", BoardFrameId::kResetEvent, 5, kResetFields, "event: why the board reset, after EVB (protocol 4)"},
};
inline constexpr uint32_t kBoardFrameCount = sizeof(kBoardFrames) / sizeof(kBoardFrames[0]);

constexpr const BoardFrameSpec& board_frame_spec(BoardFrameId id) {
  return kBoardFrames[static_cast<uint8_t>(id)];
}
constexpr bool board_frames_indexed_by_id() {
  for (uint32_t i = 0; i < kBoardFrameCount; ++i) {
    if (static_cast<uint32_t>(kBoardFrames[i].id) != i) return false;
  }
  return true;
}
static_assert(board_frames_indexed_by_id(), "kBoardFrames[i] must describe BoardFrameId i");
// Events are told from replies by the first letter of the name.
constexpr bool is_event(const BoardFrameSpec& frame) { return frame.name[0] == 'E'; }

// ---------------------------------------------------------------------------------------
// Features and the protocol version that brought each. A host asks the board's VER before it
// relies on one (hmc::Session::supports / require) and tells the user of an older board to
// reflash, instead of failing on a refusal or a frame it cannot read. Every protocol change
// raises kProtocolVersion and adds its row here.

enum class Feature : uint8_t {
  kLinkWatchdog,  // WDG, STA 7 (STW), EVD how 6
  kResetCause,    // EVR after EVB at boot, STA 8 (STR)
  kSetPosition,   // POS
  kStepBudgets,   // VER's max_ramping_rate
};

struct FeatureSpec {
  Feature feature;
  uint32_t since;        // the first protocol version that has it
  const char* name;      // stable identifier
  const char* text;      // what it is, for people
  uint32_t status_unit;  // the STA unit it brought; 0 none
};

inline constexpr FeatureSpec kFeatures[] = {
    {Feature::kLinkWatchdog, 3, "link_watchdog", "the link watchdog (WDG, STA 7)", kUnitWatchdog},
    {Feature::kResetCause, 4, "reset_cause", "the reset cause and fault record (EVR, STA 8)", kUnitReset},
    // 5 was reserved for VER's step budgets and never released: no board speaks it.
    {Feature::kSetPosition, 6, "set_position", "setting a motor's position (POS, hmc zero)", 0},
    {Feature::kStepBudgets, 7, "step_budgets", "VER's ramping step budget (max_ramping_rate)", 0},
};
inline constexpr uint32_t kFeatureCount = sizeof(kFeatures) / sizeof(kFeatures[0]);

constexpr const FeatureSpec& feature_spec(Feature f) { return kFeatures[static_cast<uint8_t>(f)]; }

constexpr bool features_indexed_and_released() {
  for (uint32_t i = 0; i < kFeatureCount; ++i) {
    if (static_cast<uint32_t>(kFeatures[i].feature) != i || kFeatures[i].since > kProtocolVersion) return false;
  }
  return true;
}
static_assert(features_indexed_and_released(),
              "kFeatures[i] describes Feature i, from a protocol version this firmware speaks");

// The feature that brought STA unit `unit`, or nullptr for the units every protocol-2 board has.
constexpr const FeatureSpec* status_unit_feature(uint32_t unit) {
  for (const FeatureSpec& f : kFeatures) {
    if (f.status_unit != 0 && f.status_unit == unit) return &f;
  }
  return nullptr;
}
// The highest STA unit a board of `protocol` answers (2: 6, 3: 7, 4: 8); above it, NAK out of range.
constexpr uint32_t status_unit_max(uint32_t protocol) {
  uint32_t last = kUnitLastBase;
  for (const FeatureSpec& f : kFeatures) {
    if (f.since <= protocol && f.status_unit > last) last = f.status_unit;
  }
  return last;
}
static_assert(status_unit_max(2) == kUnitLastBase && status_unit_max(3) == kUnitWatchdog &&
                  status_unit_max(kProtocolVersion) == kStatusFields[0].max,
              "STA's units grow one feature at a time, and this firmware answers them all");

constexpr bool is_power_of_two(uint32_t v) { return v != 0 && (v & (v - 1)) == 0; }

static_assert(kStepperFields[1].max == kActionHome, "STM's action field spans stop..home");
static_assert(sizeof(kStepperFields) / sizeof(kStepperFields[0]) == 5, "STM has 5 values");
static_assert(sizeof(kServoFields) / sizeof(kServoFields[0]) == 2, "SVM has 2 values");
static_assert(sizeof(kLedFields) / sizeof(kLedFields[0]) == 5, "LED has 5 values");
static_assert(4 + 11 + 4 + (kMaxCommandValues + 1) * 11 + 3 <= kLineMax,
              "the line buffer holds the longest frame the grammar allows");

}  // namespace hmc::proto
