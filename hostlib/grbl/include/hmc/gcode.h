// G-code as grbl 1.1 reads it, for `hmc grbl`: a line cut into words (comments and blanks
// dropped, letters upper-cased), then interpreted against the modal state (motion mode, plane,
// units, distance mode, work coordinates, feed) into what the machine is asked to do, in machine
// millimetres: straight moves (rapid or at a feed), arcs already split into straight segments
// within a tolerance, dwells, servo and LED commands (Marlin's M280 and M150), pauses and the
// program's end.
//
// Everything this front end does not do is refused with grbl's error number and a message that
// names the word (error 20 for an unsupported command), never ignored. The error numbers are
// grbl 1.1's (its doc/csv/error_codes_en_US.csv).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "hmc/result.h"

namespace hmc::grbl {

inline constexpr size_t kAxisCount = 3;  // X, Y, Z
using Vec3 = std::array<double, kAxisCount>;

// grbl's error codes that this front end reports.
enum ErrorCode : int {
  kExpectedCommandLetter = 1,
  kBadNumberFormat = 2,
  kInvalidStatement = 3,
  kNegativeValue = 4,
  kSettingDisabled = 5,
  kIdleError = 8,
  kSystemGcLock = 9,
  kSoftLimitError = 10,
  kOverflow = 11,
  kJogTravel = 15,
  kInvalidJog = 16,
  kUnsupportedCommand = 20,
  kModalGroupViolation = 21,
  kUndefinedFeedRate = 22,
  kCommandValueNotInteger = 23,
  kAxisCommandConflict = 24,
  kWordRepeated = 25,
  kNoAxisWords = 26,
  kInvalidLineNumber = 27,
  kValueWordMissing = 28,
  kUnsupportedCoordSys = 29,
  kG53InvalidMotionMode = 30,
  kAxisWordsExist = 31,
  kNoAxisWordsInPlane = 32,
  kInvalidTarget = 33,
  kArcRadiusError = 34,
  kNoOffsetsInPlane = 35,
  kUnusedWords = 36,
};

// A refusal: grbl's number and, for the [MSG:…] line, what was wrong and where.
struct GrblError {
  int code = kUnsupportedCommand;
  std::string message;
};

template <typename T>
using GrblResult = Result<T, GrblError>;

// A line reduced as grbl's line buffer holds it: comments, blanks and control bytes removed,
// letters upper-cased. `stored` counts what grbl would store (its 80-character limit applies to
// that); a byte that cannot be G-code (a control byte, 0x80 and above) is reported, not dropped.
struct CleanLine {
  std::string text;
  size_t stored = 0;
  std::optional<GrblError> garbage;
};
CleanLine clean_line(std::string_view raw);

// One word: a letter and its number, as written.
struct Word {
  char letter = 0;
  double value = 0;
  std::string text;  // "G1", "X10.5": for messages
};

// Cuts a clean line into words; error 1 (no letter), 2 (no number).
GrblResult<std::vector<Word>> split_words(std::string_view clean);

// What a line asks the machine to do, in machine millimetres, in order.
struct Move {
  Vec3 target{};        // machine position at the end
  bool rapid = false;   // G0: at the axes' maximum rate
  double feed = 0;      // mm/min (G1, G2, G3)
};
struct Dwell {
  double seconds = 0;
};
struct ServoCommand {  // M280 P<n> S<angle>: servo n+1
  uint32_t servo = 1;
  uint32_t angle = 90;
};
struct LedCommand {  // M150 S<n> R U B W [P]: strip n+1
  uint32_t strip = 1;
  uint32_t r = 0, g = 0, b = 0, w = 0;
};
struct ProgramPause {};  // M0
struct ProgramEnd {};    // M2, M30
using Step = std::variant<Move, Dwell, ServoCommand, LedCommand, ProgramPause, ProgramEnd>;

// grbl's modal state, as `$G` reports it.
struct ModalState {
  int motion = 0;         // 0 G0, 1 G1, 2 G2, 3 G3, 80 G80
  int coord_system = 0;   // 0..5: G54..G59
  bool inches = false;    // G20
  bool incremental = false;  // G91
  double feed = 0;        // mm/min; 0 undefined
};

struct InterpreterSettings {
  double arc_tolerance_mm = 0.01;  // $12: largest distance between an arc and its chords
};

// The G-code interpreter: modal state, the six work coordinate systems, the G92 offset and the
// machine position where the last interpreted move ends.
class Interpreter {
 public:
  explicit Interpreter(InterpreterSettings settings = {}) : settings_(settings) {}

  // Interprets one clean line (clean_line) into steps; on error nothing of the line applies.
  // `jog`: a `$J=` line (only G20/G21, G90/G91, G53, axis words and F; F required).
  GrblResult<std::vector<Step>> interpret(std::string_view clean, bool jog = false);

  // Where the last interpreted move ends (machine mm); set when the machine stops elsewhere.
  const Vec3& position() const { return position_; }
  void set_position(const Vec3& machine) { position_ = machine; }
  const ModalState& modal() const { return modal_; }
  // grbl's program end and soft reset: G1→G0... back to G0 G54 G17 G21 G90 G94 (offsets kept,
  // except G92's on program end as grbl does).
  void reset_modal();
  void program_end();
  // The work coordinate offset in force: G54..G59's plus G92's.
  Vec3 work_offset() const;
  const std::array<Vec3, 6>& coord_systems() const { return coord_systems_; }
  const Vec3& g92_offset() const { return g92_; }
  InterpreterSettings& settings() { return settings_; }
  const InterpreterSettings& settings() const { return settings_; }

  // "[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]"
  std::string parser_state() const;

 private:
  GrblResult<std::vector<Step>> run(const std::vector<Word>& words, bool jog);
  std::vector<Move> arc(const Vec3& start, const Vec3& end, const Vec3& offset, bool clockwise, double feed) const;

  InterpreterSettings settings_;
  ModalState modal_;
  Vec3 position_{};
  std::array<Vec3, 6> coord_systems_{};
  Vec3 g92_{};
};

// A number as grbl prints it: fixed, `decimals` places.
std::string fixed(double value, int decimals);

}  // namespace hmc::grbl
