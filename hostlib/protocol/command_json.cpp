// JSON forms of commands, board frames, diagnostics and warnings.
#include "hmc/command_json.h"

namespace hmc {
namespace {

using nlohmann::json;

// The typed fields of each board frame; the wire name is added by board_frame_to_json().
struct BoardFrameJson {
  json operator()(const Ack&) const { return json::object(); }
  json operator()(const Nak& n) const {
    const auto code = static_cast<uint32_t>(n.reason);
    return {{"reason", code < proto::kReasonCount ? json(proto::reason_spec(n.reason).name) : json(nullptr)},
            {"code", code},
            {"token", n.token == proto::kNoToken ? json(nullptr) : json(n.token)},
            {"offset", n.offset}};
  }
  json operator()(const Version& v) const {
    return {{"protocol", v.protocol},   {"firmware", v.firmware},     {"legacy", v.legacy},
            {"line_max", v.line_max},   {"max_rate", v.max_rate},     {"board", v.board},
            {"switch_mask", v.switch_mask},
            {"checksum_mode", v.checksum_mode == proto::ChecksumMode::kCrc16 ? "crc16" : "sum"},
            {"max_ramping_rate", v.max_ramping_rate ? json(*v.max_ramping_rate) : json(nullptr)}};
  }
  json operator()(const MotorStatus& s) const {
    return {{"motor", s.motor}, {"state", motor_state_name(s.state)}, {"position", s.position},
            {"target", s.target}, {"rate", s.rate}, {"homed", s.homed}, {"switches", s.switches},
            {"endless", s.endless}, {"microstep", s.microstep}};
  }
  json operator()(const BoardStatus& b) const {
    return {{"emergency", b.emergency}, {"limits", b.limits}, {"servo1_us", b.servo1_us}, {"servo2_us", b.servo2_us}};
  }
  json operator()(const StripStatus& s) const {
    return {{"strip", s.strip}, {"r", s.r}, {"g", s.g}, {"b", s.b}, {"w", s.w}};
  }
  json operator()(const SettingValue& s) const {
    return {{"motor", s.motor}, {"setting", s.setting}, {"value", s.value}};
  }
  json operator()(const Booted& b) const { return {{"protocol", b.protocol}, {"firmware", b.firmware}}; }
  json operator()(const MotionEnded& e) const {
    return {{"motor", e.motor}, {"how", motion_end_name(e.how)}, {"position", e.position}};
  }
  json operator()(const HomingEnded& h) const {
    return {{"motor", h.motor}, {"homed", h.homed}, {"position", h.position}};
  }
  json operator()(const LimitChanged& l) const { return {{"motor", l.motor}, {"end", l.end}, {"pressed", l.pressed}}; }
  json operator()(const EmergencyChanged& e) const { return {{"pressed", e.pressed}}; }
  json operator()(const DriverFault& f) const { return {{"motor", f.motor}, {"status", f.status}}; }
  json operator()(const WatchdogStatus& w) const { return {{"timeout_ms", w.timeout_ms}, {"fired", w.fired}}; }
  json operator()(const ResetInfo& r) const {
    return {{"cause", reset_cause_name(r.cause)}, {"exception", r.exception}, {"pc", r.pc}, {"lr", r.lr},
            {"context", r.context}};
  }
};

}  // namespace

json command_to_json(const Command& command) {
  const proto::CommandSpec& spec = command_spec(command);
  const CommandValues v = command_values(command);
  json out = {{"name", spec.name}};
  for (uint32_t i = 0; i < v.count; ++i) out[spec.fields[i].name] = v.values[i];
  return out;
}

json board_frame_to_json(const BoardFrame& frame) {
  json out = std::visit(BoardFrameJson{}, frame);
  out["name"] = board_frame_spec(frame).name;
  return out;
}

json diagnostic_to_json(const Diagnostic& d) {
  json out = {{"reason", proto::reason_spec(d.reason).name},
              {"code", static_cast<int>(d.reason)},
              {"offset", d.offset},
              {"message", d.message}};
  out["token"] = d.token == kNoToken ? json(nullptr) : json(d.token);
  out["field"] = d.field;
  out["expected"] = d.expected;
  out["found"] = d.found;
  return out;
}

json warnings_to_json(const std::vector<Warning>& warnings) {
  json out = json::array();
  for (const Warning& w : warnings) out.push_back({{"field", w.field}, {"message", w.message}});
  return out;
}

}  // namespace hmc
