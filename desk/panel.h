// Panel: the window's contents, drawn once a frame from a snapshot of the board worker. It keeps
// only what the person types (port, speeds, colours, the motion file's path); everything it
// shows of the board comes from the snapshot, and everything it does is a request to the worker.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "board_worker.h"
#include "gamepad.h"
#include "saved_positions.h"
#include "script.h"

namespace hmc::desk {

class Panel {
 public:
  // `profile` (may be null) names the axes and gives their units; `gamepad` is read once a frame.
  Panel(BoardWorker& worker, ScriptDriver* script, std::string port, uint32_t baud, const Profile* profile,
        GamepadSource& gamepad);
  // Draws the whole window (width × height pixels). `focused`: the window has the keyboard; the
  // gamepad drives nothing without it.
  void draw(float width, float height, bool focused);
  // The ports offered in the port list: the system's serial ports and two simulated boards.
  void refresh_ports();

 private:
  struct MotorInputs {
    int speed = 1000;  // steps/s
    int accel = 0;     // steps/s², 0: constant rate
    int steps = 1600;  // the Move field
    std::string go_to;  // the Go to field: a position in the axis's units
    bool holding[2] = {false, false};  // hold to run: forward, reverse, held last frame
  };
  struct StripInputs {
    float rgb[3] = {0, 0, 0};
    int w = 0;
  };

  void top_bar(float width);
  void motor_panel(uint32_t m, float width, float height);
  void servo_panel(float width, float height);
  void switch_panel(float width, float height);
  void led_panel(float width, float height);
  void file_panel(float width, float height);
  void log_panel(float width, float height);
  void positions_panel(float width, float height);
  void save_positions();
  // The keys of `hmc jog` (hmc/jog.h), when no text field has the keyboard.
  void keyboard_jog();
  void gamepad_jog(bool focused);
  void stop_all();
  // Requests for motor m carrying its panel's speed and acceleration.
  Request motor_request(Request::Kind kind, uint32_t m) const;
  Axis axis_of(uint32_t m, bool* described = nullptr) const;
  // The profile's absolute path: its saved positions are listed under it ("" without a profile).
  std::string profile_key() const;

  // A button the script can click too: its key is the group (if any) and the visible label.
  bool button(const char* label, float width = 0, float height = 0);
  std::string key(const char* label) const;
  bool connected() const { return snap_.link == LinkState::kConnected; }

  BoardWorker& worker_;
  ScriptDriver* script_;
  const Profile* profile_;
  GamepadSource& gamepad_;
  GamepadJog stick_;
  bool pad_present_ = false;
  size_t jog_level_;       // the jog step's index (hmc/jog.h)
  size_t jog_axis_ = 0;    // the axis jogged last: z zeroes it
  std::optional<SavedPositions> positions_;
  std::string positions_where_;  // the file, or why there is none
  std::string positions_error_;  // why the last change could not be written
  std::string position_name_;
  Snapshot snap_;
  std::string group_;  // "motor 1", "LED 2" ...: the prefix of widget keys while drawing one
  // Inputs
  std::string port_;
  int baud_;
  std::vector<std::string> ports_;
  std::array<MotorInputs, proto::kMotorCount> motors_{};
  std::array<int, proto::kServoCount> servo_angle_{90, 90};
  std::array<StripInputs, proto::kStripCount> strips_{};
  std::string file_path_;
  uint64_t log_seen_ = 0;
};

}  // namespace hmc::desk
