// The grbl front end's reports (grbl.h): the `?` status report, `$$` settings and `$N=` changes
// (to the running front end only), `$#` parameters.
#include "grbl_shared.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace hmc::grbl {

using namespace detail;

// ---- reports -------------------------------------------------------------------------------

SessionResult<Done> FrontEnd::status_report() {
  // Positions of moving motors are asked for: events only say where a motion ended.
  for (uint32_t m = 1; m <= proto::kMotorCount; ++m) {
    if (!moving(session_.model().motor(m))) continue;
    if (SessionResult<BoardFrame> status = session_.execute(StatusQuery{m}); !status) return status.error();
  }
  const double unit = report_inches_ ? kMmPerInch : 1.0;
  const int decimals = report_inches_ ? 4 : 3;
  const Vec3 wco = interpreter_.work_offset();
  std::string r = "<";
  r += state_name(state_);
  if (state_ == State::kHold) r += hold_stopped_ ? ":0" : ":1";
  r += report_mpos_ ? "|MPos:" : "|WPos:";
  double feed_sq = 0;
  for (size_t a = 0; a < kAxisCount; ++a) {
    const double pos = machine_mm(a) - (report_mpos_ ? 0 : wco[a]);
    r += (a ? "," : "") + fmt(pos / unit, decimals);
    if (axes_[a].axis) {
      const MotorStatus& m = session_.model().motor(axes_[a].axis->motor);
      const double v = axes_[a].axis->from_board_rate(m.rate, m.microstep);
      feed_sq += v * v;
    }
  }
  if (report_buffer_) {
    r += "|Bf:" + std::to_string(kPlannerBlocks - std::min(queue_.size(), kPlannerBlocks)) + "," +
         std::to_string(kRxBufferSize);
  }
  r += "|FS:" + fmt(std::sqrt(feed_sq) * 60.0 / unit, 0) + ",0";
  std::string pins;
  for (size_t a = 0; a < kAxisCount; ++a) {
    if (axes_[a].axis && session_.model().motor(axes_[a].axis->motor).switches != 0) pins += kLetters[a];
  }
  if (!pins.empty()) r += "|Pn:" + pins;
  // grbl sends the work offset every 10 reports, and at once when it changed.
  if (!last_wco_ || *last_wco_ != wco || reports_ % 10 == 0) {
    r += "|WCO:" + fmt(wco[0] / unit, decimals) + "," + fmt(wco[1] / unit, decimals) + "," + fmt(wco[2] / unit, decimals);
    last_wco_ = wco;
  }
  ++reports_;
  r += ">";
  send(r);
  return Done{};
}

std::string FrontEnd::settings_text() const {
  uint32_t dir_mask = 0, homing_mask = 0;
  double seek = 0, locate = 0, pull_off = 0;
  for (size_t a = 0; a < kAxisCount; ++a) {
    const std::optional<Axis>& axis = axes_[a].axis;
    if (!axis) continue;
    if (axis->invert) dir_mask |= 1u << a;
    if (axis->homing) {
      // grbl homes toward +, unless its bit in $23 is set: the switch end in the axis's sense.
      const bool toward_negative = (axis->homing->end == 0) != axis->invert;
      if (toward_negative) homing_mask |= 1u << a;
      if (seek == 0) {
        seek = axis->homing->seek_speed.value_or(0) * 60;
        locate = axis->homing->locate_speed.value_or(0) * 60;
        pull_off = axis->homing->pull_off.value_or(0);
      }
    }
  }
  std::string s;
  const auto line = [&s](int n, const std::string& v) { s += "$" + std::to_string(n) + "=" + v + "\r\n"; };
  line(0, "10");
  line(1, "255");
  line(2, "0");
  line(3, std::to_string(dir_mask));
  line(4, "0");
  line(5, "0");
  line(6, "0");
  line(10, std::to_string((report_mpos_ ? 1 : 0) | (report_buffer_ ? 2 : 0)));
  line(11, "0.000");
  line(12, fmt(interpreter_.settings().arc_tolerance_mm));
  line(13, report_inches_ ? "1" : "0");
  line(20, soft_limits_ ? "1" : "0");
  line(21, "1");
  line(22, homing_ ? "1" : "0");
  line(23, std::to_string(homing_mask));
  line(24, fmt(locate));
  line(25, fmt(seek));
  line(26, "0");
  line(27, fmt(pull_off));
  line(30, "0");
  line(31, "0");
  line(32, "0");
  for (size_t a = 0; a < kAxisCount; ++a) line(100 + static_cast<int>(a), fmt(axes_[a].axis ? axes_[a].axis->steps_per_unit() : 0));
  for (size_t a = 0; a < kAxisCount; ++a) line(110 + static_cast<int>(a), fmt(axes_[a].max_rate));
  for (size_t a = 0; a < kAxisCount; ++a) line(120 + static_cast<int>(a), fmt(axes_[a].accel));
  for (size_t a = 0; a < kAxisCount; ++a) line(130 + static_cast<int>(a), fmt(axes_[a].max_travel));
  return s;
}

void FrontEnd::setting(const std::string& c) {
  if ((state_ != State::kIdle && state_ != State::kAlarm) || current_ || !queue_.empty()) {
    error(GrblError{kIdleError, "settings change only while the machine is idle"});
    return;
  }
  const size_t eq = c.find('=');
  if (eq == std::string::npos) {
    error(GrblError{kInvalidStatement, c + ": a setting is written $N=value"});
    return;
  }
  char* end = nullptr;
  const long n = std::strtol(c.c_str() + 1, &end, 10);
  if (end != c.c_str() + eq) {
    error(GrblError{kInvalidStatement, c + ": a setting is written $N=value"});
    return;
  }
  const std::string text = c.substr(eq + 1);
  char* value_end = nullptr;
  const double v = std::strtod(text.c_str(), &value_end);
  if (text.empty() || value_end != text.c_str() + text.size()) {
    error(GrblError{kBadNumberFormat, "$" + std::to_string(n) + "=" + text + ": not a number"});
    return;
  }
  if (v < 0) {
    error(GrblError{kNegativeValue, "$" + std::to_string(n) + ": must not be negative"});
    return;
  }
  const auto axis_of = [&](long first) -> GrblAxis* {
    const auto a = static_cast<size_t>(n - first);
    return axes_[a].axis ? &axes_[a] : nullptr;
  };
  const auto absent = [&]() {
    error(GrblError{kInvalidStatement, "$" + std::to_string(n) + ": the profile has no axis " +
                                           std::string(1, kLetters[static_cast<size_t>(n % 10)])});
  };
  if (n == 10) {
    report_mpos_ = (static_cast<int>(v) & 1) != 0;
    report_buffer_ = (static_cast<int>(v) & 2) != 0;
  } else if (n == 12) {
    if (v <= 0) {
      error(GrblError{kInvalidStatement, "$12: the arc tolerance must be above 0"});
      return;
    }
    interpreter_.settings().arc_tolerance_mm = v;
  } else if (n == 13) {
    report_inches_ = v != 0;
  } else if (n == 20) {
    if (v != 0 && !homing_) {
      error(GrblError{kSoftLimitError, "soft limits need homing enabled ($22=1)"});
      return;
    }
    soft_limits_ = v != 0;
    if (SessionResult<Done> sent = send_soft_limits(); !sent) message("soft limits not sent: " + sent.error().message);
  } else if (n == 22) {
    bool can_home = false;
    for (const GrblAxis& g : axes_) can_home = can_home || (g.axis && g.axis->homing && g.axis->motor <= 2);
    if (v != 0 && !can_home) {
      error(GrblError{kSettingDisabled, "no axis of the profile homes ([axis.NAME.homing], motors 1 and 2)"});
      return;
    }
    homing_ = v != 0;
  } else if (n == 24 || n == 25 || n == 27) {
    for (GrblAxis& g : axes_) {
      if (!g.axis || !g.axis->homing) continue;
      AxisHoming& h = *g.axis->homing;
      if (n == 24) h.locate_speed = v / 60.0;
      if (n == 25) h.seek_speed = v / 60.0;
      if (n == 27) h.pull_off = v;
    }
  } else if (n >= 100 && n <= 102) {
    GrblAxis* g = axis_of(100);
    if (g == nullptr) return absent();
    if (v <= 0) {
      error(GrblError{kInvalidStatement, "$" + std::to_string(n) + ": steps per mm must be above 0"});
      return;
    }
    g->axis->mm_per_rev = g->axis->steps_per_rev_out() / v;
    resync();
  } else if (n >= 110 && n <= 112) {
    GrblAxis* g = axis_of(110);
    if (g == nullptr) return absent();
    if (v <= 0) {
      error(GrblError{kInvalidStatement, "$" + std::to_string(n) + ": the maximum rate must be above 0"});
      return;
    }
    g->max_rate = v;
  } else if (n >= 120 && n <= 122) {
    GrblAxis* g = axis_of(120);
    if (g == nullptr) return absent();
    g->accel = v;
  } else if (n >= 130 && n <= 132) {
    GrblAxis* g = axis_of(130);
    if (g == nullptr) return absent();
    g->max_travel = v;
    if (!g->axis->limit_min) g->axis->limit_min = 0.0;
    g->axis->limit_max = *g->axis->limit_min + v;
    if (SessionResult<Done> sent = send_soft_limits(); !sent) message("soft limits not sent: " + sent.error().message);
  } else {
    const bool known = (n >= 0 && n <= 6) || n == 11 || n == 21 || n == 23 || n == 26 || (n >= 30 && n <= 32);
    error(GrblError{kInvalidStatement, "$" + std::to_string(n) +
                                           (known ? ": fixed by the board and the profile here (docs/grbl.md)"
                                                  : ": no such setting")});
    return;
  }
  message("$" + std::to_string(n) + " changed for this hmc grbl only: the profile file is not written");
  ok();
}

std::string FrontEnd::parameters_text() const {
  std::string s;
  const double unit = report_inches_ ? kMmPerInch : 1.0;
  const int decimals = report_inches_ ? 4 : 3;
  const auto vec = [&](const Vec3& v) {
    return fmt(v[0] / unit, decimals) + "," + fmt(v[1] / unit, decimals) + "," + fmt(v[2] / unit, decimals);
  };
  for (size_t k = 0; k < 6; ++k) s += "[G" + std::to_string(54 + k) + ":" + vec(interpreter_.coord_systems()[k]) + "]\r\n";
  s += "[G28:" + vec(Vec3{}) + "]\r\n";
  s += "[G30:" + vec(Vec3{}) + "]\r\n";
  s += "[G92:" + vec(interpreter_.g92_offset()) + "]\r\n";
  s += "[TLO:" + fmt(0, decimals) + "]\r\n";
  s += "[PRB:" + vec(Vec3{}) + ":0]\r\n";
  return s;
}

}  // namespace hmc::grbl
