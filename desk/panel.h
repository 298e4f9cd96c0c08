// Panel: the window's contents, drawn once a frame from a snapshot of the board worker. It keeps
// only what the person types (port, speeds, colours, the motion file's path); everything it
// shows of the board comes from the snapshot, and everything it does is a request to the worker.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "board_worker.h"
#include "script.h"

namespace hmc::desk {

class Panel {
 public:
  Panel(BoardWorker& worker, ScriptDriver* script, std::string port, uint32_t baud);
  // Draws the whole window (width × height pixels).
  void draw(float width, float height);
  // The ports offered in the port list: the system's serial ports and two simulated boards.
  void refresh_ports();

 private:
  struct MotorInputs {
    int speed = 1000;  // steps/s
    int accel = 0;     // steps/s², 0: constant rate
    int steps = 1600;  // the Move field
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

  // A button the script can click too: its key is the group (if any) and the visible label.
  bool button(const char* label, float width = 0, float height = 0);
  std::string key(const char* label) const;
  bool connected() const { return snap_.link == LinkState::kConnected; }

  BoardWorker& worker_;
  ScriptDriver* script_;
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
