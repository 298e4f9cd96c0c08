// Panel: the layout and widgets of hmc-desk (see panel.h).
#include "panel.h"

#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <utility>

#include "hmc/axis_moves.h"
#include "hmc/jog.h"
#include "hmc/port_list.h"
#include "hmc/units.h"

namespace hmc::desk {
namespace {

constexpr uint32_t kFullStepsPerRev = 200;
constexpr float kPad = 8.0f;
const ImVec4 kRed{0.80f, 0.16f, 0.16f, 1.0f};
const ImVec4 kRedHover{0.92f, 0.22f, 0.22f, 1.0f};
const ImVec4 kRedActive{0.65f, 0.10f, 0.10f, 1.0f};
const ImVec4 kGreen{0.30f, 0.78f, 0.38f, 1.0f};
const ImVec4 kAmber{0.95f, 0.70f, 0.20f, 1.0f};
const ImVec4 kGrey{0.55f, 0.57f, 0.60f, 1.0f};
const ImVec4 kBlue{0.45f, 0.65f, 0.95f, 1.0f};

const char* state_name(MotorState s) {
  switch (s) {
    case MotorState::kIdle: return "idle";
    case MotorState::kMoving: return "moving";
    case MotorState::kHoming: return "homing";
    case MotorState::kChanging: return "changing";
    case MotorState::kSelfTest: return "self-test";
  }
  return "?";
}

// A filled circle on the current line, then `text`.
void indicator(bool on, const ImVec4& on_colour, const char* text) {
  const float r = ImGui::GetTextLineHeight() * 0.42f;
  const ImVec2 p = ImGui::GetCursorScreenPos();
  const ImVec2 centre{p.x + r + 1, p.y + ImGui::GetTextLineHeight() * 0.5f};
  ImDrawList* draw = ImGui::GetWindowDrawList();
  draw->AddCircleFilled(centre, r, ImGui::GetColorU32(on ? on_colour : ImVec4{0.25f, 0.27f, 0.30f, 1.0f}));
  draw->AddCircle(centre, r, ImGui::GetColorU32(kGrey));
  ImGui::Dummy(ImVec2{2 * r + 6, ImGui::GetTextLineHeight()});
  ImGui::SameLine();
  ImGui::TextUnformatted(text);
}

// The velocity of a track at time t (piecewise linear between its points).
float velocity_at(const motion::MotorTrack& track, double t) {
  const std::vector<motion::VelocityPoint>& v = track.velocity;
  if (v.empty() || t < v.front().t_s || t > v.back().t_s) return 0.0f;
  auto after = std::lower_bound(v.begin(), v.end(), t, [](const motion::VelocityPoint& p, double x) { return p.t_s < x; });
  if (after == v.begin()) return static_cast<float>(after->velocity);
  auto before = after - 1;
  const double span = after->t_s - before->t_s;
  if (span <= 0) return static_cast<float>(after->velocity);
  return static_cast<float>(before->velocity + (after->velocity - before->velocity) * (t - before->t_s) / span);
}

void section_title(const char* text) {
  ImGui::PushStyleColor(ImGuiCol_Text, kBlue);
  ImGui::TextUnformatted(text);
  ImGui::PopStyleColor();
  ImGui::Separator();
}

}  // namespace

Panel::Panel(BoardWorker& worker, ScriptDriver* script, std::string port, uint32_t baud, const Profile* profile,
             GamepadSource& gamepad)
    : worker_(worker),
      script_(script),
      profile_(profile),
      gamepad_(gamepad),
      jog_level_(kJogFirstStep),
      port_(std::move(port)),
      baud_(static_cast<int>(baud)) {
  // A profile axis starts at its own speed and acceleration, in steps at its microstep.
  for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
    const Axis* axis = profile_ != nullptr ? profile_->axis_of_motor(m) : nullptr;
    if (axis == nullptr) continue;
    if (axis->speed) motors_[m - 1].speed = std::clamp(static_cast<int>(std::lround(*axis->speed * axis->steps_per_unit())), 1, 50000);
    if (axis->accel) motors_[m - 1].accel = std::clamp(static_cast<int>(std::lround(*axis->accel * axis->steps_per_unit())), 0, 1000000);
  }
  if (Result<std::string> path = SavedPositions::default_path(); !path) {
    positions_where_ = path.error().message;
  } else if (Result<SavedPositions> loaded = SavedPositions::load(*path, profile_key()); !loaded) {
    positions_where_ = loaded.error().message;
  } else {
    positions_ = std::move(*loaded);
    positions_where_ = *path;
  }
  strips_[0].rgb[0] = 1.0f;
  strips_[0].rgb[1] = 0.55f;
  strips_[1].rgb[2] = 1.0f;
  refresh_ports();
  if (port_.empty()) port_ = ports_.empty() ? "sim://desk" : ports_.front();
}

void Panel::refresh_ports() {
  ports_.clear();
  if (Result<std::vector<PortInfo>> found = list_ports(); found) {
    for (const PortInfo& p : *found) ports_.push_back(p.name);
  }
  ports_.push_back("sim://desk");
  ports_.push_back("sim://desk?seed");
}

std::string Panel::key(const char* label) const {
  std::string visible(label);
  if (const size_t hashes = visible.find("##"); hashes != std::string::npos) visible.resize(hashes);
  return group_.empty() ? visible : group_ + "/" + visible;
}

bool Panel::button(const char* label, float width, float height) {
  const bool clicked = ImGui::Button(label, ImVec2{width, height});
  return clicked || (script_ && script_->take_click(key(label)));
}

std::string Panel::profile_key() const {
  if (profile_ == nullptr) return "";
  char* real = realpath(profile_->path.c_str(), nullptr);
  if (real == nullptr) return profile_->path;
  std::string path(real);
  std::free(real);
  return path;
}

Axis Panel::axis_of(uint32_t m, bool* described) const {
  return BoardWorker::axis_of(profile_, m, snap_.model.motor(m).microstep, described);
}

Request Panel::motor_request(Request::Kind kind, uint32_t m) const {
  Request r(kind);
  r.unit = m;
  r.rate = static_cast<uint32_t>(std::max(1, motors_[m - 1].speed));
  r.accel = static_cast<uint32_t>(std::max(0, motors_[m - 1].accel));
  return r;
}

void Panel::stop_all() {
  worker_.stop_all();
  stick_.halt();
}

void Panel::keyboard_jog() {
  const ImGuiIO& io = ImGui::GetIO();
  if (io.WantTextInput) return;  // the keys are the text field's
  std::vector<JogKey> keys;
  static const std::pair<ImGuiKey_, JogArrow> kArrows[] = {
      {ImGuiKey_RightArrow, JogArrow::kRight}, {ImGuiKey_LeftArrow, JogArrow::kLeft}, {ImGuiKey_UpArrow, JogArrow::kUp},
      {ImGuiKey_DownArrow, JogArrow::kDown},   {ImGuiKey_PageUp, JogArrow::kPageUp},  {ImGuiKey_PageDown, JogArrow::kPageDown}};
  for (const auto& [key, arrow] : kArrows) {
    if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(key), true)) keys.push_back(jog_arrow_key(arrow, io.KeyShift));
  }
  for (const ImWchar c : io.InputQueueCharacters) {
    if (c >= 0x80) continue;
    if (const std::optional<JogKey> key = jog_char_key(static_cast<char>(c))) keys.push_back(*key);
  }
  for (const JogKey& key : keys) {
    switch (key.kind) {
      case JogKey::Kind::kMove: {
        if (!connected()) break;
        jog_axis_ = key.axis;
        Request r = motor_request(Request::Kind::kJog, static_cast<uint32_t>(key.axis) + 1);
        r.dir = key.dir;
        r.fast = key.fast;
        r.level = jog_level_;
        worker_.post(r);
        break;
      }
      case JogKey::Kind::kStepUp: jog_level_ = std::min(jog_level_ + 1, kJogProfileSteps.size() - 1); break;
      case JogKey::Kind::kStepDown: jog_level_ = jog_level_ == 0 ? 0 : jog_level_ - 1; break;
      case JogKey::Kind::kStopAll: stop_all(); break;
      case JogKey::Kind::kZero:
        if (connected()) worker_.post(motor_request(Request::Kind::kZero, static_cast<uint32_t>(jog_axis_) + 1));
        break;
      default: break;  // q and Ctrl-C end `hmc jog`; the window closes as windows do
    }
  }
}

void Panel::gamepad_jog(bool focused) {
  const GamepadState state = gamepad_.read();
  pad_present_ = state.present;
  const bool trusted = focused && connected() && !snap_.running;
  for (const StickCommand& c : stick_.update(state, trusted)) {
    const uint32_t m = static_cast<uint32_t>(c.axis) + 1;
    switch (c.kind) {
      case StickCommand::Kind::kStopAll: worker_.stop_all(); break;
      case StickCommand::Kind::kStop:
        if (connected()) worker_.post(motor_request(Request::Kind::kStop, m));
        break;
      case StickCommand::Kind::kRun: {
        Request r = motor_request(Request::Kind::kStickRun, m);
        r.reverse = c.fraction < 0;
        r.rate = static_cast<uint32_t>(std::max(1L, std::lround(std::fabs(c.fraction) * r.rate)));
        worker_.post(r);
        break;
      }
    }
  }
  if (stick_.running()) worker_.stick_heartbeat();
}

void Panel::draw(float width, float height, bool focused) {
  snap_ = worker_.snapshot();
  // Escape is STOP ALL wherever the focus is.
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape), false)) stop_all();
  keyboard_jog();
  gamepad_jog(focused);

  ImGui::SetNextWindowPos(ImVec2{0, 0});
  ImGui::SetNextWindowSize(ImVec2{width, height});
  ImGui::Begin("hmc-desk", nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoSavedSettings |
                   ImGuiWindowFlags_NoBringToFrontOnFocus);
  top_bar(width);
  ImGui::Spacing();

  const float content_w = ImGui::GetContentRegionAvail().x;
  const float content_h = ImGui::GetContentRegionAvail().y;
  const float right_w = 390.0f;
  const float left_w = content_w - right_w - kPad;
  const float motors_h = 384.0f;

  ImGui::BeginGroup();
  const float motor_w = (left_w - 2 * kPad) / 3.0f;
  for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
    if (m > 1) ImGui::SameLine(0, kPad);
    motor_panel(m, motor_w, motors_h);
  }
  const float lower_h = content_h - motors_h - kPad;
  const float side_w = 300.0f;
  ImGui::BeginGroup();
  servo_panel(side_w, lower_h * 0.5f - kPad * 0.5f);
  switch_panel(side_w, lower_h * 0.5f - kPad * 0.5f);
  ImGui::EndGroup();
  ImGui::SameLine(0, kPad);
  led_panel(left_w - side_w - kPad, lower_h);
  ImGui::EndGroup();

  ImGui::SameLine(0, kPad);
  ImGui::BeginGroup();
  const float file_h = 270.0f, positions_h = 210.0f;
  file_panel(right_w, file_h);
  positions_panel(right_w, positions_h);
  log_panel(right_w, content_h - file_h - positions_h - 2 * kPad);
  ImGui::EndGroup();
  ImGui::End();
}

void Panel::top_bar(float width) {
  const bool busy_link = snap_.link == LinkState::kConnecting;
  ImGui::AlignTextToFramePadding();
  ImGui::TextUnformatted("Port");
  ImGui::SameLine();
  ImGui::SetNextItemWidth(250);
  if (script_) {
    if (auto text = script_->take_text("Port")) port_ = *text;
  }
  ImGui::InputText("##port", &port_);
  ImGui::SameLine(0, 2);
  if (ImGui::BeginCombo("##ports", nullptr, ImGuiComboFlags_NoPreview | ImGuiComboFlags_PopupAlignLeft)) {
    for (const std::string& p : ports_) {
      if (ImGui::Selectable(p.c_str(), p == port_)) port_ = p;
    }
    if (ImGui::Selectable("(look for ports again)")) refresh_ports();
    ImGui::EndCombo();
  }
  ImGui::SameLine();
  ImGui::TextUnformatted("Baud");
  ImGui::SameLine();
  ImGui::SetNextItemWidth(90);
  static const int kBauds[] = {9600, 19200, 38400, 57600, 115200, 230400, 460800, 921600};
  const std::string baud_text = std::to_string(baud_);
  if (ImGui::BeginCombo("##baud", baud_text.c_str())) {
    for (const int b : kBauds) {
      if (ImGui::Selectable(std::to_string(b).c_str(), b == baud_)) baud_ = b;
    }
    ImGui::EndCombo();
  }
  ImGui::SameLine();
  if (connected()) {
    if (button("Disconnect", 100)) worker_.post(Request(Request::Kind::kDisconnect));
  } else {
    ImGui::BeginDisabled(busy_link);
    if (button("Connect", 100)) {
      Request r(Request::Kind::kConnect);
      r.text = port_;
      r.baud = static_cast<uint32_t>(baud_);
      worker_.post(r);
    }
    ImGui::EndDisabled();
  }
  ImGui::SameLine(0, 16);
  switch (snap_.link) {
    case LinkState::kDisconnected: indicator(false, kGrey, "not connected"); break;
    case LinkState::kConnecting: indicator(true, kAmber, "connecting..."); break;
    case LinkState::kConnected: indicator(true, kGreen, "connected"); break;
    case LinkState::kFailed: indicator(true, kRed, "connection failed (see the log)"); break;
  }
  if (snap_.link == LinkState::kConnected) {
    ImGui::SameLine(0, 16);
    const bool seed = snap_.firmware == Firmware::kSeed;
    ImGui::PushStyleColor(ImGuiCol_Text, seed ? kAmber : kGreen);
    ImGui::Text("%s", seed ? "SEED" : "V2");
    ImGui::PopStyleColor();
    ImGui::SameLine();
    ImGui::TextDisabled("firmware %s", snap_.firmware_version.c_str());
  }

  // STOP ALL: at the right, always there, always enabled.
  const float stop_w = 170.0f;
  ImGui::SameLine(width - stop_w - ImGui::GetStyle().WindowPadding.x);
  ImGui::PushStyleColor(ImGuiCol_Button, kRed);
  ImGui::PushStyleColor(ImGuiCol_ButtonHovered, kRedHover);
  ImGui::PushStyleColor(ImGuiCol_ButtonActive, kRedActive);
  ImGui::PushStyleColor(ImGuiCol_Text, ImVec4{1, 1, 1, 1});
  const float y = ImGui::GetCursorPosY();
  ImGui::SetCursorPosY(y - 4);
  if (button("STOP ALL", stop_w, ImGui::GetFrameHeight() + 8)) stop_all();
  ImGui::PopStyleColor(4);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Stops every motor now (Escape)");
  if (connected() && !snap_.description.empty()) {
    ImGui::TextDisabled("%s", snap_.description.c_str());
  } else {
    ImGui::TextDisabled("%s", "choose a port (sim://desk is a simulated board) and connect");
  }
  ImGui::Separator();
}

void Panel::motor_panel(uint32_t m, float width, float height) {
  group_ = "motor " + std::to_string(m);
  MotorInputs& in = motors_[m - 1];
  const MotorStatus& status = snap_.model.motor(m);
  ImGui::BeginChild(group_.c_str(), ImVec2{width, height}, true);
  ImGui::PushID(static_cast<int>(m));

  bool described = false;
  const Axis axis = axis_of(m, &described);
  const std::string unit = unit_name(axis.unit());
  ImGui::PushStyleColor(ImGuiCol_Text, kBlue);
  if (described) {
    ImGui::Text("Motor %u \xc2\xb7 %s", m, axis.name.c_str());
  } else {
    ImGui::Text("Motor %u", m);
  }
  ImGui::PopStyleColor();
  ImGui::SameLine();
  const bool moving = status.state != MotorState::kIdle;
  ImGui::SameLine(width - 110);
  indicator(moving, status.state == MotorState::kHoming ? kAmber : kGreen, connected() ? state_name(status.state) : "-");
  ImGui::Separator();

  // Positions arrive in 1/256 step. A profile axis shows its own units first (mm, deg), the
  // steps beside; a bare motor its steps at its microstep and the shaft's angle.
  const double full_steps = static_cast<double>(status.position) / 256.0;
  const double steps = full_steps * status.microstep;
  ImGui::SetWindowFontScale(1.45f);
  if (described) {
    ImGui::Text("%s %s", number_text(axis.from_board_position(status.position)).c_str(), unit.c_str());
  } else {
    ImGui::Text("%.0f", steps);
  }
  ImGui::SetWindowFontScale(1.0f);
  ImGui::SameLine();
  ImGui::AlignTextToFramePadding();
  if (described) {
    ImGui::TextDisabled("%.0f steps (1/%u)", steps, status.microstep);
    ImGui::Text("%s %s/s", number_text(axis.from_board_rate(status.rate, status.microstep)).c_str(), unit.c_str());
  } else {
    ImGui::TextDisabled("steps (1/%u)", status.microstep);
    ImGui::Text("%.2f\xc2\xb0", full_steps / kFullStepsPerRev * 360.0);
  }
  ImGui::SameLine();
  ImGui::TextDisabled("| %u steps/s | %s%s", status.rate, status.homed ? "homed" : "not homed",
                      status.endless ? " | run" : "");
  if (described && axis.limit_min) {
    ImGui::TextDisabled("soft limits %s to %s %s%s", number_text(*axis.limit_min).c_str(), number_text(*axis.limit_max).c_str(),
                        unit.c_str(), status.homed ? "" : " (once homed or zeroed)");
  } else {
    ImGui::TextDisabled("%s", described ? "no soft limits" : "no profile axis: steps");
  }

  ImGui::Spacing();
  ImGui::BeginDisabled(!connected());
  static const int kJogs[] = {-100, -10, -1, 1, 10, 100};
  constexpr float kJogGap = 4.0f;
  const float jog_w = (ImGui::GetContentRegionAvail().x - 5 * kJogGap) / 6.0f;
  ImGui::PushStyleVar(ImGuiStyleVar_FramePadding, ImVec2{1, ImGui::GetStyle().FramePadding.y});
  for (size_t i = 0; i < 6; ++i) {
    if (i > 0) ImGui::SameLine(0, kJogGap);
    char label[16];
    std::snprintf(label, sizeof label, "%+d", kJogs[i]);
    if (button(label, jog_w)) {
      Request r = motor_request(Request::Kind::kMove, m);
      r.steps = kJogs[i];
      worker_.post(r);
    }
  }
  ImGui::PopStyleVar();
  // Hold to run: a run until stopped while the button is down, a stop when it is let go.
  const float half = (ImGui::GetContentRegionAvail().x - ImGui::GetStyle().ItemSpacing.x) / 2.0f;
  for (int d = 0; d < 2; ++d) {
    if (d > 0) ImGui::SameLine();
    const char* label = d == 0 ? "<< hold rev" : "hold fwd >>";
    ImGui::Button(label, ImVec2{half, 0});
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Runs while held, stops when let go");
    const bool held = connected() && (ImGui::IsItemActive() || (script_ && script_->held(key(label))));
    if (held && !in.holding[d]) {
      Request r = motor_request(Request::Kind::kRun, m);
      r.reverse = d == 0;
      worker_.post(r);
    } else if (!held && in.holding[d]) {
      Request r(Request::Kind::kStop);
      r.unit = m;
      worker_.post(r);
    }
    in.holding[d] = held;
  }
  ImGui::EndDisabled();

  ImGui::Spacing();
  const float label_w = 92.0f;
  auto int_input = [&](const char* label, const char* id, int& value, int lo, int hi) {
    if (script_) {
      if (auto v = script_->take_values(key(id))) {
        if (!v->empty()) value = static_cast<int>(std::lround((*v)[0]));
      }
    }
    ImGui::AlignTextToFramePadding();
    ImGui::TextUnformatted(label);
    ImGui::SameLine(label_w);
    ImGui::SetNextItemWidth(-1);
    ImGui::InputInt((std::string("##") + id).c_str(), &value, 0, 0);
    value = std::clamp(value, lo, hi);
  };
  int_input("Speed /s", "speed", in.speed, 1, 50000);
  int_input("Accel /s\xc2\xb2", "accel", in.accel, 0, 1000000);
  if (script_) {
    if (auto v = script_->take_values(key("steps"))) {
      if (!v->empty()) in.steps = static_cast<int>(std::lround((*v)[0]));
    }
  }
  ImGui::AlignTextToFramePadding();
  ImGui::TextUnformatted("Move by");
  ImGui::SameLine(label_w);
  ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x - 70);
  ImGui::InputInt("##steps", &in.steps, 0, 0);
  ImGui::SameLine();
  ImGui::BeginDisabled(!connected());
  if (button("Move", -1)) {
    Request r = motor_request(Request::Kind::kMove, m);
    r.steps = in.steps;
    worker_.post(r);
  }
  ImGui::EndDisabled();
  // An absolute target in the axis's units (a bare number), or any unit it takes ("2rev").
  if (script_) {
    if (auto text = script_->take_text(key("go to"))) in.go_to = *text;
  }
  ImGui::AlignTextToFramePadding();
  ImGui::TextUnformatted("Go to");
  ImGui::SameLine(label_w);
  ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x - 70);
  ImGui::InputTextWithHint("##go to", described ? unit.c_str() : "steps", &in.go_to);
  ImGui::SameLine();
  ImGui::BeginDisabled(!connected() || in.go_to.empty());
  if (button("Go", -1)) {
    Request r = motor_request(Request::Kind::kGoTo, m);
    r.text = in.go_to;
    worker_.post(r);
  }
  ImGui::EndDisabled();
  ImGui::BeginDisabled(!connected());

  // Home (motors 1 and 2, which have switches), Stop and Set zero here on one row.
  const bool has_home = m <= 2;
  const float gap = ImGui::GetStyle().ItemSpacing.x;
  const float row_w = ImGui::GetContentRegionAvail().x;
  const float small_w = has_home ? (row_w - 2 * gap) * 0.28f : (row_w - gap) * 0.4f;
  if (has_home) {
    if (button("Home", small_w)) worker_.post(motor_request(Request::Kind::kHome, m));
    ImGui::SameLine();
  }
  if (button("Stop", small_w)) worker_.post(motor_request(Request::Kind::kStop, m));
  ImGui::SameLine();
  if (button("Set zero here", -1)) worker_.post(motor_request(Request::Kind::kZero, m));
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("This position becomes 0 (protocol 6); the profile's soft limits apply from now");
  ImGui::EndDisabled();
  ImGui::PopID();
  ImGui::EndChild();
  group_.clear();
}

void Panel::servo_panel(float width, float height) {
  ImGui::BeginChild("servos", ImVec2{width, height}, true);
  section_title("Servos");
  for (uint32_t s = 1; s <= proto::kServoCount; ++s) {
    group_ = "servo " + std::to_string(s);
    ImGui::PushID(static_cast<int>(s));
    const uint32_t pulse = s == 1 ? snap_.model.board.servo1_us : snap_.model.board.servo2_us;
    int& angle = servo_angle_[s - 1];
    bool send = false;
    if (script_) {
      if (auto v = script_->take_values(key("angle")); v && !v->empty()) {
        angle = static_cast<int>(std::lround((*v)[0]));
        send = true;
      }
    }
    ImGui::Text("%s", s == 1 ? "Servo 1 (pan)" : "Servo 2 (tilt)");
    ImGui::SameLine(width - 120);
    if (pulse == 0) {
      ImGui::TextDisabled("released");
    } else {
      // The board reports the pulse; the angle it stands for (protocol_facts.h servo_pulse_us).
      const double now = (static_cast<double>(pulse) - 544.0) * 180.0 / 1856.0;
      ImGui::TextDisabled("now %.0f\xc2\xb0", now);
    }
    ImGui::BeginDisabled(!connected());
    ImGui::SetNextItemWidth(-1);
    ImGui::SliderInt("##angle", &angle, 10, 170, "%d\xc2\xb0");
    // Sent when the slider is let go: one SVM per gesture, not one per frame.
    if (ImGui::IsItemDeactivatedAfterEdit()) send = true;
    ImGui::EndDisabled();
    if (send && connected()) {
      Request r(Request::Kind::kServo);
      r.unit = s;
      r.angle = static_cast<uint32_t>(angle);
      worker_.post(r);
    }
    ImGui::PopID();
    ImGui::Spacing();
  }
  group_.clear();
  ImGui::EndChild();
}

void Panel::switch_panel(float width, float height) {
  ImGui::BeginChild("switches", ImVec2{width, height}, true);
  section_title("Switches");
  const BoardStatus& b = snap_.model.board;
  if (ImGui::BeginTable("limits", 2)) {
    for (uint32_t m = 1; m <= 2; ++m) {
      for (uint32_t end = 0; end < 2; ++end) {
        ImGui::TableNextColumn();
        char text[48];
        std::snprintf(text, sizeof text, "M%u %s", m, end == 0 ? "reverse" : "forward");
        indicator(b.limit_pressed(m, end), kAmber, text);
      }
    }
    ImGui::EndTable();
  }
  ImGui::Spacing();
  indicator(b.emergency, kRed, b.emergency ? "EMERGENCY STOP PRESSED" : "emergency switch released");
  ImGui::EndChild();
}

void Panel::led_panel(float width, float height) {
  ImGui::BeginChild("leds", ImVec2{width, height}, true);
  section_title("LED strips");
  const float strip_w = (ImGui::GetContentRegionAvail().x - kPad) / 2.0f;
  for (uint32_t s = 1; s <= proto::kStripCount; ++s) {
    group_ = "LED " + std::to_string(s);
    StripInputs& in = strips_[s - 1];
    if (script_) {
      if (auto v = script_->take_values(key("colour")); v && v->size() >= 3) {
        for (size_t i = 0; i < 3; ++i) in.rgb[i] = static_cast<float>((*v)[i] / 255.0);
        if (v->size() >= 4) in.w = static_cast<int>(std::lround((*v)[3]));
      }
    }
    if (s > 1) ImGui::SameLine(0, kPad);
    ImGui::BeginGroup();
    ImGui::PushID(static_cast<int>(s));
    const StripStatus& now = snap_.model.strips[s - 1];
    ImGui::Text("Strip %u", s);
    ImGui::SameLine();
    // What the board shows now, as a swatch.
    ImGui::ColorButton("##now",
                       ImVec4{static_cast<float>(now.r) / 255.0f, static_cast<float>(now.g) / 255.0f,
                              static_cast<float>(now.b) / 255.0f, 1.0f},
                       ImGuiColorEditFlags_NoTooltip, ImVec2{40, 0});
    ImGui::SameLine();
    ImGui::TextDisabled("now %u %u %u W%u", now.r, now.g, now.b, now.w);
    ImGui::SetNextItemWidth(std::min(strip_w, height - 120));
    ImGui::ColorPicker3("##pick", in.rgb,
                        ImGuiColorEditFlags_NoSidePreview | ImGuiColorEditFlags_PickerHueBar |
                            ImGuiColorEditFlags_DisplayRGB | ImGuiColorEditFlags_NoLabel);
    ImGui::AlignTextToFramePadding();
    ImGui::TextUnformatted("W");
    ImGui::SameLine();
    ImGui::SetNextItemWidth(strip_w - 100);
    ImGui::SliderInt("##w", &in.w, 0, 255);
    ImGui::SameLine();
    ImGui::BeginDisabled(!connected());
    if (button("Apply", 70)) {
      Request r(Request::Kind::kLed);
      r.unit = s;
      r.r = static_cast<uint32_t>(std::lround(in.rgb[0] * 255.0f));
      r.g = static_cast<uint32_t>(std::lround(in.rgb[1] * 255.0f));
      r.b = static_cast<uint32_t>(std::lround(in.rgb[2] * 255.0f));
      r.w = static_cast<uint32_t>(std::clamp(in.w, 0, 255));
      worker_.post(r);
    }
    ImGui::EndDisabled();
    ImGui::PopID();
    ImGui::EndGroup();
  }
  group_.clear();
  ImGui::EndChild();
}

void Panel::file_panel(float width, float height) {
  group_ = "file";
  ImGui::BeginChild("file", ImVec2{width, height}, true);
  section_title("Motion file");
  if (script_) {
    if (auto text = script_->take_text(key("path"))) file_path_ = *text;
  }
  ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x - 160);
  ImGui::InputTextWithHint("##path", "path/to/file.json", &file_path_);
  ImGui::SameLine();
  if (button("Open", 60)) worker_.post(Request(Request::Kind::kOpenFile, file_path_));
  ImGui::SameLine();
  if (button("Validate", -1)) worker_.post(Request(Request::Kind::kOpenFile, file_path_));

  const LoadedFile& f = snap_.file;
  if (!f.errors.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, kRed);
    ImGui::BeginChild("errors", ImVec2{-1, 120}, false, ImGuiWindowFlags_HorizontalScrollbar);
    for (const std::string& e : f.errors) ImGui::TextUnformatted(e.c_str());
    ImGui::EndChild();
    ImGui::PopStyleColor();
  } else if (f.plan) {
    const motion::Plan& plan = *f.plan;
    ImGui::TextDisabled("%zu steps, %.1f s; velocity (steps/s) of each motor:", plan.actions.size(), plan.duration_s);
    const size_t tracks = std::max<size_t>(plan.tracks.size(), 1);
    const float plot_h = std::max(30.0f, (height - 175.0f) / static_cast<float>(tracks) - 4.0f);
    constexpr int kSamples = 240;
    for (const motion::MotorTrack& t : plan.tracks) {
      std::vector<float> v(kSamples);
      float top = 1.0f;
      for (int i = 0; i < kSamples; ++i) {
        v[static_cast<size_t>(i)] = velocity_at(t, plan.duration_s * i / (kSamples - 1));
        top = std::max(top, std::fabs(v[static_cast<size_t>(i)]));
      }
      char overlay[96];
      std::snprintf(overlay, sizeof overlay, "%s (motor %u), peak %.0f", t.name.c_str(), t.motor, top);
      ImGui::PlotLines(("##" + t.name).c_str(), v.data(), kSamples, 0, overlay, -top, top,
                     ImVec2{ImGui::GetContentRegionAvail().x, plot_h});
    }
  } else {
    ImGui::TextDisabled("Open a motion file (examples/*.json) to see its plan.");
  }

  // Run, progress, stop: pinned to the bottom of the panel.
  ImGui::SetCursorPosY(height - ImGui::GetFrameHeightWithSpacing() * 2 - ImGui::GetStyle().WindowPadding.y);
  const float progress = snap_.run_total ? static_cast<float>(snap_.run_done) / static_cast<float>(snap_.run_total) : 0.0f;
  char overlay[160];
  if (snap_.running) {
    std::snprintf(overlay, sizeof overlay, "%zu/%zu  %.1f s left  %s", snap_.run_done, snap_.run_total,
                  snap_.run_remaining_s, snap_.run_action.c_str());
  } else {
    std::snprintf(overlay, sizeof overlay, "%s", snap_.run_total ? "not running (last run shown)" : "not running");
  }
  ImGui::ProgressBar(progress, ImVec2{-1, 0}, overlay);
  ImGui::BeginDisabled(!connected() || !f.plan || snap_.running);
  const float half = (ImGui::GetContentRegionAvail().x - ImGui::GetStyle().ItemSpacing.x) / 2.0f;
  if (button("Run", half)) worker_.post(Request(Request::Kind::kRunFile));
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::BeginDisabled(!snap_.running);
  if (button("Stop run", -1)) worker_.stop_run();
  ImGui::EndDisabled();
  ImGui::EndChild();
  group_.clear();
}

void Panel::save_positions() {
  const Status written = positions_->save();
  positions_error_ = written ? std::string() : "not saved: " + written.error().message;
}

void Panel::positions_panel(float width, float height) {
  group_ = "positions";
  ImGui::BeginChild("positions", ImVec2{width, height}, true);
  section_title("Jog and saved positions");
  // The keys, as `hmc jog` has them, with the step now.
  bool described = false;
  const Axis last = axis_of(static_cast<uint32_t>(jog_axis_) + 1, &described);
  const std::string step = described ? number_text(kJogProfileSteps[jog_level_]) + " " + unit_name(last.unit())
                                     : number_text(kJogMotorSteps[jog_level_]) + " steps";
  ImGui::TextDisabled("keys \xe2\x86\x90\xe2\x86\x92\xe2\x86\x91\xe2\x86\x93 PgUp/Dn jog, Shift x10, step %s (+/-)", step.c_str());
  ImGui::TextDisabled("space stops all, z zeroes %s", last.name.c_str());
  ImGui::TextDisabled("gamepad: %s", pad_present_ ? (stick_.running() ? "running" : "sticks jog, B stops all") : "none");

  if (!positions_) {
    ImGui::TextWrapped("positions cannot be saved: %s", positions_where_.c_str());
    ImGui::EndChild();
    group_.clear();
    return;
  }
  if (script_) {
    if (auto text = script_->take_text(key("name"))) position_name_ = *text;
  }
  ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x - 110);
  ImGui::InputTextWithHint("##name", "name this position", &position_name_);
  ImGui::SameLine();
  ImGui::BeginDisabled(!connected() || position_name_.empty());
  if (button("Save here", -1)) {
    // Every axis where it is now, in its own units (bare motors in steps).
    SavedPosition saved{position_name_, {}};
    for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
      bool is_axis = false;
      const Axis axis = axis_of(m, &is_axis);
      const int64_t position = snap_.model.motor(m).position;
      saved.axes[axis.name] = is_axis ? axis.from_board_position(position)
                                      : static_cast<double>(position) * snap_.model.motor(m).microstep / 256.0;
    }
    positions_->put(std::move(saved));
    save_positions();
  }
  ImGui::EndDisabled();
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Saved in %s", positions_where_.c_str());
  if (!positions_error_.empty()) ImGui::TextColored(kRed, "%s", positions_error_.c_str());

  ImGui::BeginChild("list", ImVec2{-1, -1}, false);
  std::optional<std::string> forget;
  for (const SavedPosition& p : positions_->list()) {
    group_ = "positions/" + p.name;
    ImGui::PushID(p.name.c_str());
    std::string where;  // motor 1's axis first
    for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
      bool is_axis = false;
      const Axis axis = axis_of(m, &is_axis);
      const auto value = p.axes.find(axis.name);
      if (value == p.axes.end()) continue;
      where += (where.empty() ? "" : ", ") + axis.name + " " + number_text(value->second) + " " +
               (is_axis ? unit_name(axis.unit()) : "steps");
    }
    ImGui::BeginDisabled(!connected());
    if (button("Go to", 60)) {
      // Absolute targets, each in the unit it was saved in: rounding never adds up.
      for (const auto& [name, value] : p.axes) {
        const Axis* axis = profile_ != nullptr ? profile_->find(name) : nullptr;
        uint32_t m = axis != nullptr ? axis->motor : 0;
        if (axis == nullptr && name.rfind("motor ", 0) == 0) m = static_cast<uint32_t>(std::atoi(name.c_str() + 6));
        if (m < 1 || m > proto::kMotorCount) continue;  // an axis this profile does not have
        Request r = motor_request(Request::Kind::kGoTo, m);
        r.text = number_text(value, 6) + (axis != nullptr ? unit_name(axis->unit()) : "steps");
        worker_.post(r);
      }
    }
    ImGui::EndDisabled();
    ImGui::SameLine();
    if (button("Forget", 60)) forget = p.name;
    ImGui::SameLine();
    ImGui::Text("%s", p.name.c_str());
    ImGui::SameLine();
    ImGui::TextDisabled("%s", where.c_str());
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", where.c_str());
    ImGui::PopID();
  }
  ImGui::EndChild();
  group_ = "positions";
  if (forget) {
    positions_->remove(*forget);
    save_positions();
  }
  ImGui::EndChild();
  group_.clear();
}

void Panel::log_panel(float width, float height) {
  ImGui::BeginChild("log_frame", ImVec2{width, height}, true);
  section_title("Event log");
  ImGui::BeginChild("log", ImVec2{-1, -1}, false, ImGuiWindowFlags_HorizontalScrollbar);
  const bool at_bottom = ImGui::GetScrollY() >= ImGui::GetScrollMaxY() - 4.0f;
  for (const LogLine& line : snap_.log) {
    ImVec4 colour = ImGui::GetStyleColorVec4(ImGuiCol_Text);
    switch (line.kind) {
      case LogLine::Kind::kInfo: break;
      case LogLine::Kind::kSent: colour = kGrey; break;
      case LogLine::Kind::kReply: colour = ImVec4{0.55f, 0.75f, 0.60f, 1.0f}; break;
      case LogLine::Kind::kEvent: colour = kAmber; break;
      case LogLine::Kind::kError: colour = ImVec4{1.0f, 0.42f, 0.42f, 1.0f}; break;
    }
    ImGui::TextDisabled("%7.2f", line.t_s);
    ImGui::SameLine();
    ImGui::PushStyleColor(ImGuiCol_Text, colour);
    ImGui::TextUnformatted(line.text.c_str());
    ImGui::PopStyleColor();
  }
  // Newest at the bottom: follow it, unless the person scrolled up to read.
  if (snap_.log_serial != log_seen_ && at_bottom) ImGui::SetScrollHereY(1.0f);
  log_seen_ = snap_.log_serial;
  ImGui::EndChild();
  ImGui::EndChild();
}

}  // namespace hmc::desk
