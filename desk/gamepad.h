// The gamepad, behind a seam: a GamepadSource gives the pad's sticks and buttons once a frame —
// GLFW's gamepad API for a real pad (GlfwGamepads), or values a test script sets
// (ScriptedGamepad), since no pad exists where the tests run. GamepadJog turns what the pad says
// into runs and stops: hold a stick and its axis runs at a rate proportional to how far it leans
// (past a dead zone); let go and it stops; B stops everything. When the pad cannot be trusted any
// more — it is unplugged, the window loses the focus or closes — every axis it started stops.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace hmc::desk {

// GLFW's gamepad layout (GLFW_GAMEPAD_AXIS_*, GLFW_GAMEPAD_BUTTON_*), copied by value so that
// this header needs no GLFW: the sticks' axes run -1..1, Y positive downwards.
struct GamepadState {
  enum Axis : size_t { kLeftX = 0, kLeftY = 1, kRightX = 2, kRightY = 3, kAxisCount = 6 };
  enum Button : size_t { kA = 0, kB = 1, kButtonCount = 15 };
  bool present = false;  // a pad with a gamepad mapping is plugged in
  std::array<float, kAxisCount> axes{};
  std::array<bool, kButtonCount> buttons{};
};

class GamepadSource {
 public:
  virtual ~GamepadSource() = default;
  virtual GamepadState read() = 0;
};

// The first joystick GLFW knows a gamepad mapping for (glfwGetGamepadState).
class GlfwGamepads : public GamepadSource {
 public:
  GamepadState read() override;
};

// The pad a test script holds: "stick LX 0.8", "button B down".
class ScriptedGamepad : public GamepadSource {
 public:
  GamepadState read() override { return state_; }
  GamepadState& state() { return state_; }

 private:
  GamepadState state_;
};

// What the pad asks for this frame.
struct StickCommand {
  enum class Kind : uint8_t { kRun, kStop, kStopAll };
  Kind kind = Kind::kStop;
  size_t axis = 0;        // kRun, kStop: 0 the first axis (left stick X), 1 the second (left stick Y, up +),
                          // 2 the third (right stick Y, up +)
  double fraction = 0;    // kRun: -1..1 of the axis's jog speed, in kLevels steps
};

class GamepadJog {
 public:
  static constexpr float kDeadZone = 0.15f;  // a stick at rest reads up to about 0.1 on worn pads
  static constexpr int kLevels = 8;          // rate steps: a run is re-sent only when the level changes
  static constexpr size_t kAxes = 3;

  // One frame. `trusted` false (the window has no focus, is closing, nothing is connected, a
  // motion file runs): every axis the pad runs is stopped and none starts.
  std::vector<StickCommand> update(const GamepadState& state, bool trusted);
  bool running() const;
  // Everything was stopped another way (STOP ALL, space, Escape): a stick still held does not
  // start its axis again until it has been let go.
  void halt();

  // The level (-kLevels..kLevels) a stick value asks for.
  static int level_of(float value);

 private:
  std::array<int, kAxes> level_{};
  std::array<bool, kAxes> blocked_{};  // halted while held: waits for the stick to come back
  bool stop_held_ = false;
};

}  // namespace hmc::desk
