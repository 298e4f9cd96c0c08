// The gamepad seam and its jog rules (see gamepad.h).
#include "gamepad.h"

#include <GLFW/glfw3.h>

#include <cmath>

namespace hmc::desk {

static_assert(GamepadState::kLeftX == GLFW_GAMEPAD_AXIS_LEFT_X && GamepadState::kLeftY == GLFW_GAMEPAD_AXIS_LEFT_Y &&
              GamepadState::kRightY == GLFW_GAMEPAD_AXIS_RIGHT_Y && GamepadState::kAxisCount == GLFW_GAMEPAD_AXIS_LAST + 1);
static_assert(GamepadState::kB == GLFW_GAMEPAD_BUTTON_B && GamepadState::kButtonCount == GLFW_GAMEPAD_BUTTON_LAST + 1);

GamepadState GlfwGamepads::read() {
  GamepadState out;
  for (int jid = GLFW_JOYSTICK_1; jid <= GLFW_JOYSTICK_LAST; ++jid) {
    GLFWgamepadstate pad;
    if (glfwJoystickIsGamepad(jid) == GLFW_FALSE || glfwGetGamepadState(jid, &pad) == GLFW_FALSE) continue;
    out.present = true;
    for (size_t i = 0; i < out.axes.size(); ++i) out.axes[i] = pad.axes[i];
    for (size_t i = 0; i < out.buttons.size(); ++i) out.buttons[i] = pad.buttons[i] == GLFW_PRESS;
    break;
  }
  return out;
}

int GamepadJog::level_of(float value) {
  const float lean = (std::fabs(value) - kDeadZone) / (1.0f - kDeadZone);
  if (!(lean > 0)) return 0;  // inside the dead zone (or not a number)
  const int level = static_cast<int>(std::ceil(std::fmin(lean, 1.0f) * kLevels));
  return value < 0 ? -level : level;
}

bool GamepadJog::running() const {
  for (const int level : level_) {
    if (level != 0) return true;
  }
  return false;
}

void GamepadJog::halt() {
  for (size_t a = 0; a < kAxes; ++a) {
    blocked_[a] = blocked_[a] || level_[a] != 0;
    level_[a] = 0;
  }
}

std::vector<StickCommand> GamepadJog::update(const GamepadState& state, bool trusted) {
  std::vector<StickCommand> out;
  const bool stop_pressed = state.present && state.buttons[GamepadState::kB];
  if (stop_pressed && !stop_held_) {
    out.push_back({StickCommand::Kind::kStopAll, 0, 0});
    halt();
  }
  stop_held_ = stop_pressed;
  // Up is negative on GLFW's Y axes; up is an axis's positive direction here, as the Up key's.
  const std::array<float, kAxes> sticks{state.axes[GamepadState::kLeftX], -state.axes[GamepadState::kLeftY],
                                        -state.axes[GamepadState::kRightY]};
  for (size_t a = 0; a < kAxes; ++a) {
    const int lean = state.present ? level_of(sticks[a]) : 0;
    // Untrusted, a held stick is stopped (below) and stays so until let go: no run starts by itself
    // when the focus comes back.
    if (!trusted && (level_[a] != 0 || lean != 0)) blocked_[a] = true;
    const int wanted = trusted && !stop_pressed && !blocked_[a] ? lean : 0;
    if (wanted != level_[a]) {
      out.push_back(wanted == 0 ? StickCommand{StickCommand::Kind::kStop, a, 0}
                                : StickCommand{StickCommand::Kind::kRun, a, static_cast<double>(wanted) / kLevels});
      level_[a] = wanted;
    }
    if (blocked_[a] && lean == 0) blocked_[a] = false;  // let go: the stick may start it again
  }
  return out;
}

}  // namespace hmc::desk
