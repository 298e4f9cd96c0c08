// Controller: the board's behaviour. It reads command lines from the serial port, decides what
// each accepted frame does and which rules refuse it, and owns every output: the steppers
// (through StepScheduler and the DRV8711 drivers), servos, LED strips, buzzer and booting LEDs.
//
// Rules (seed 003, 모터 동작 시 유의사항; docs/protocol.md "What the board does"):
//  - STM forward/reverse moves `steps` steps (0: until stopped) at `microstep` and `delay_us` per
//    step; a new STM for a running motor replaces its move; dir 0 stops it (braking when the
//    motor has an acceleration); dir 3 homes motors 1-2: reverse toward switch end 0 until it
//    closes, then the position is zero. A microstep change while running stops the motor
//    first, writes MODE while it rests, then starts the new move.
//  - [1] a move toward a pressed limit switch is refused; a switch closing during a move toward
//    it halts that motor at once. [2] homing starts only while every motor rests.
//  - [3] fixed: every motor keeps its own rate. [5] lifted: servo and LED frames work while
//    steppers run; Options::legacy restores the seed's refusal.
//  - The emergency switch halts every motor at once (no braking) and, while pressed, refuses
//    STM moves and homing and SVM. Stops and LED frames still work.
//  - The board's step interrupt has a budget (kMaxStepRate): a move whose rate would take the
//    sum of the commanded rates above it is refused, as is a delay the timer cannot count.
//  - Every refused line sounds the warning tone. With Options::replies every line is answered
//    in order (reply_writer.h): ACK, NAK with the reason, token and offset, or the answer to a
//    query (VER, STA → STA/STB/STL/STW/STR, GET → SET); events (EVB and EVR at boot, EVD, EVH,
//    EVL, EVE, EVF) are sent as things happen. Without replies the board is silent, as the seed is.
//  - The link watchdog (protocol 3, WDG): armed with a timeout, the board brakes every motor
//    (EVD how 6) when no line has ended for that long, then stays disarmed until armed again;
//    STA 7 reports it (STW), with whether it fired since it was last armed. Off at boot.
//  - Why the board last reset (protocol 4): EVR right after EVB at boot, STR for STA 8.
//  - Protocol v2 settings per motor (SET/GET, proto::kSettings): current, decay, acceleration,
//    max rate, homing end, seek rate, pull-off and slow locate; soft limits (LIM); the checksum
//    mode (CRC), switched after its own ACK.
// Contexts: boot() and poll() run in the main loop; on_step_timer() is the step timer's
// interrupt; on_switch_change() is the switches' interrupt (lower priority than the step timer).
// Freestanding: no heap; every buffer is a member.
#pragma once

#include <stdint.h>

#include "drv8711.h"
#include "frame_parser.h"
#include "hal.h"
#include "protocol_facts.h"
#include "step_scheduler.h"

namespace hmc::fw {

// The hardware the controller drives.
struct Board {
  hal::StepTimer& timer;
  hal::StepPins& pins;
  hal::SpiBus& spi;
  hal::ServoPwm& servos;
  hal::LedStrips& leds;
  hal::Switches& switches;
  hal::Buzzer& buzzer;
  hal::BootLeds& boot_leds;
  hal::SerialPort& serial;
};

// Why the board last reset and, after a fault, where (EVR and STR, proto::kResetFields): the
// port reads it from the chip before boot().
struct ResetReport {
  proto::ResetCause cause = proto::ResetCause::kUnknown;
  uint32_t exception = 0;  // the exception that caught a fault (3 HardFault, 16 + n interrupt n)
  uint32_t pc = 0;         // the faulting instruction
  uint32_t lr = 0;         // the link register then, bit 31 dropped
  uint32_t context = 0;    // what ran then: 0 the main loop, else its exception number
};

struct ControllerOptions {
  bool legacy = false;     // seed rule [5]: SVM and LED refused while any stepper runs
  bool replies = true;     // answer every line; false: the seed's silence
  bool self_test = true;   // at boot: each stepper half a turn forward and back, servos centred
};

// Sum of the commanded step rates of all moving motors the step interrupt is given, in steps/s
// (proto::step_budget: the host explains refusals with the same numbers).
inline constexpr uint32_t kMaxStepRate = proto::kMaxStepRate;

// Homing with delay 0 uses the setting home_seek_us (500 µs at boot), microstep 0 keeps the
// current microstep (the spec's `STX#6#STM#1#3#0#0#0#4#ETX`). Current and decay at boot are the
// settings' initial values (proto::kSettings: 1000 mA, a safe current for any 36v4-driven
// motor; auto-mixed decay, the seed's).
inline constexpr uint32_t kBootMicrostep = 16;     // MODE written at boot
// A servo's pulse train stops this long after its last SVM (the seed detaches to stop jitter;
// 160° at a typical 0.1 s/60° takes ≈ 0.27 s).
inline constexpr uint32_t kServoHoldMs = 500;
inline constexpr uint32_t kBootLedPeriodMs = 1000;
// DRV8711 STATUS is read this often; a new fault is reported once (EVF).
inline constexpr uint32_t kDriverCheckMs = 100;
// Self-test: half a turn (100 full steps) at kBootMicrostep, forward then back.
inline constexpr uint32_t kSelfTestSteps = 100 * kBootMicrostep;
inline constexpr uint32_t kSelfTestDelayUs = 250;

// Buzzer tunes.
struct Note {
  uint16_t hz;
  uint16_t ms;
};
inline constexpr Note kBootTune[] = {{1500, 120}, {2500, 120}};
inline constexpr Note kWarningTune[] = {{800, 200}};

using proto::servo_pulse_us;

enum class MotorState : uint8_t {
  kIdle,
  kMoving,    // a counted move or a run until stopped
  kHoming,    // seeking switch end 0
  kChanging,  // stopping to change microstep; the next move waits in `pending`
  kSelfTest,
};

class Controller {
 public:
  Controller(const Board& board, const ControllerOptions& options);

  // Main loop, once: drivers set up and enabled, LEDs off, servos centred, boot tune, booting
  // LEDs, the boot events (EVB, then EVR with `reset`), self-test.
  void boot(const ResetReport& reset);
  // Main loop, as often as possible: serial bytes, lines, timers, ended motions, switches.
  void poll();
  // The step timer's interrupt.
  void on_step_timer() { scheduler_.on_step_timer(); }
  // What the board's own step interrupt plays (step_engine.h), instead of on_step_timer().
  StepEngine& step_engine() { return scheduler_.engine(); }
  // The switches' interrupt: halts a motor moving toward a switch that closed, or all of them
  // on the emergency switch. The main loop then finishes the bookkeeping.
  void on_switch_change();

  // Per-motor acceleration in steps/s² (0: constant rate, the seed's behaviour) for moves that
  // start after the call, as SET accel does. False for a bad motor or value.
  bool set_acceleration(uint8_t motor, uint32_t steps_per_s2);

  // For the simulator, tests and status.
  MotorState state(uint8_t motor) const { return motors_[index(motor)].state; }
  int32_t position(uint8_t motor) const { return scheduler_.position(motor); }  // 1/256 step
  uint32_t microstep(uint8_t motor) const { return motors_[index(motor)].microstep; }
  bool homed(uint8_t motor) const { return motors_[index(motor)].homed; }
  bool self_test_running() const { return self_test_phase_ != 0; }
  uint32_t setting(uint8_t motor, uint8_t id) const { return motors_[index(motor)].settings[id - 1]; }
  proto::ChecksumMode checksum_mode() const { return parser_.checksum_mode(); }
  uint32_t lines_accepted() const { return accepted_; }
  uint32_t lines_refused() const { return refused_; }
  // The link watchdog: its timeout (0 off) and when it fires unless a line ends first.
  uint32_t watchdog_ms() const { return watchdog_ms_; }
  hal::Ticks watchdog_due() const { return watchdog_at_; }
  const StepScheduler& scheduler() const { return scheduler_; }
  const drv8711::Drv8711& driver(uint8_t motor) const { return drivers_[index(motor)]; }

 private:
  enum class HomePhase : uint8_t { kSeek, kPullOff, kLocate };
  struct Motor {
    MotorState state;
    uint32_t microstep;      // MODE last written
    uint32_t rate;           // commanded steps/s of the current move, 0 at rest
    uint32_t seen_finished;  // scheduler.finished() last handled
    bool homed;
    volatile uint8_t toward; // switch end the motor moves toward: 0, 1, or kNoEnd
    volatile uint8_t halt_cause;  // proto::kEndLimit / kEndEmergency when a switch halted it
    bool reverse;            // direction of the move last started
    HomePhase home_phase;
    uint32_t home_delay_us;  // the seek's delay, reused by the pull-off
    MoveSpec pending;        // kChanging: the move to start once the motor rests
    uint32_t pending_rate;
    MotorState pending_state;
    uint32_t settings[proto::kSettingCount];
    bool soft_limits;        // low < high
    int64_t soft_low, soft_high;
    uint8_t fault_reported;  // DRV8711 STATUS bits last reported
  };
  // A rule's verdict on an accepted frame: kOk, or the reason and the token it concerns.
  struct Refusal {
    proto::Reason reason = proto::Reason::kOk;
    uint8_t token = proto::kNoToken;
  };
  static constexpr uint8_t kNoEnd = 0xFF;
  static uint8_t index(uint8_t motor) { return static_cast<uint8_t>(motor - 1u); }

  // controller.cpp: lines, servos, LEDs, queries, settings, switches, timers, events.
  void handle_line(const Verdict& verdict);
  Refusal execute(const Command& command);
  Refusal servo(const ServoCommand& command);
  Refusal led(const LedCommand& command);
  Refusal set(const SettingCommand& command);
  Refusal limits(const LimitsCommand& command);
  Refusal set_position(const PositionCommand& command);
  void answer_version();
  void answer_status(uint8_t unit);
  void check_watchdog(hal::Ticks now);
  void send_reset(proto::BoardFrameId id);  // EVR or STR
  void check_switches();
  void check_drivers(hal::Ticks now);
  void run_timers(hal::Ticks now);
  void play(const Note* tune, uint8_t count);
  void next_note(hal::Ticks now);
  void send(proto::BoardFrameId id, const uint32_t* values);
  void send_motion_ended(uint8_t motor, uint32_t how);
  void send_homing_ended(uint8_t motor, bool homed);

  // controller_motion.cpp: moves, homing, the rate budget, soft limits, the self-test.
  Refusal stepper(const StepperCommand& command);
  Refusal home(const StepperCommand& command);
  proto::Reason start_move(uint8_t motor, const MoveSpec& move, uint32_t rate, MotorState state);
  bool within_budget(uint8_t motor, uint32_t rate, uint32_t accel) const;
  bool any_moving() const;
  void stop_motor(uint8_t motor);
  void check_motions();
  void motion_ended(uint8_t motor);
  void homing_step(uint8_t motor);
  void start_self_test();
  void abort_self_test();
  void advance_self_test();

  Board board_;
  ControllerOptions options_;
  StepScheduler scheduler_;
  drv8711::Drv8711 drivers_[proto::kMotorCount];
  FrameParser parser_;
  Motor motors_[proto::kMotorCount];

  bool emergency_;
  bool limits_[proto::kMotorCount][2];
  hal::Ticks servo_release_at_[proto::kServoCount];  // 0: no pulse running
  uint16_t servo_pulse_[proto::kServoCount];         // µs, 0 released
  uint8_t strips_[proto::kStripCount][4];            // r, g, b, w
  hal::Ticks driver_check_at_;
  uint32_t watchdog_ms_;         // 0: off
  hal::Ticks watchdog_at_;       // when it fires unless a line ends first
  bool watchdog_fired_;          // since it was last armed
  proto::ChecksumMode next_mode_;                    // CRC: applied after the line's reply
  ResetReport reset_;
  hal::Ticks boot_led_at_;
  bool boot_led_left_;
  const Note* tune_;
  uint8_t tune_left_;
  hal::Ticks tune_next_at_;
  uint8_t self_test_phase_;  // 0 none, 1 forward, 2 back
  uint32_t accepted_;
  uint32_t refused_;
};

}  // namespace hmc::fw
