// Plots of a Plan (motion_plan.h): velocity over time as a self-contained SVG, one panel per
// motor on a shared time axis, and the same points as CSV for other tools.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "hmc/motion_plan.h"

namespace hmc::motion {
namespace {

// Page layout, in px.
constexpr double kWidth = 1000;
constexpr double kLeft = 84;     // room for the velocity labels
constexpr double kRight = 24;
constexpr double kTop = 74;      // title, subtitle, action numbers
constexpr double kHeader = 20;   // a panel's name and positions, above its plot
constexpr double kPanel = 150;
constexpr double kGap = 14;
constexpr double kBottom = 52;   // time labels and axis name
constexpr double kMinLabelGap = 14;  // action numbers closer than this share a label
constexpr double kMinLineGap = 2;    // vertical lines closer than this to the last are left out

const char* const kColours[] = {"#1f6feb", "#d1495b", "#2a9d63"};  // motors 1, 2, 3
const char* const kFont = "font-family=\"Helvetica, Arial, sans-serif\"";

std::string fixed(double x, int decimals = 1) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, x);
  return buf;
}

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

// A 1-2-5 tick spacing giving about `count` intervals over `range`.
double nice_step(double range, int count) {
  const double raw = range / count;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / mag;
  return (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * mag;
}

int decimals_for(double step) { return step >= 1 ? 0 : static_cast<int>(std::ceil(-std::log10(step) - 1e-9)); }

std::string tick_label(double v, double step) {
  if (std::fabs(v) < step * 1e-6) v = 0;
  return fixed(v, decimals_for(step));
}

// The points to draw: per half-pixel column only the first, lowest, highest and last, in time
// order, so a long plan draws the same picture from a bounded number of points.
template <typename XOf>
std::vector<VelocityPoint> thinned(const std::vector<VelocityPoint>& points, const XOf& x_of) {
  std::vector<VelocityPoint> out;
  for (size_t i = 0; i < points.size();) {
    const double column = std::floor(x_of(points[i].t_s) * 2);
    size_t j = i, lo = i, hi = i;
    while (j < points.size() && std::floor(x_of(points[j].t_s) * 2) == column) {
      if (points[j].velocity < points[lo].velocity) lo = j;
      if (points[j].velocity > points[hi].velocity) hi = j;
      ++j;
    }
    size_t keep[4] = {i, std::min(lo, hi), std::max(lo, hi), j - 1};
    for (size_t k = 0; k < 4; ++k) {
      if (k == 0 || keep[k] != keep[k - 1]) out.push_back(points[keep[k]]);
    }
    i = j;
  }
  return out;
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

}  // namespace

std::string plot_svg(const Plan& plan, const std::string& title) {
  const double plot_w = kWidth - kLeft - kRight;
  const size_t panels = std::max<size_t>(plan.tracks.size(), 1);
  auto panel_top = [](size_t p) { return kTop + static_cast<double>(p) * (kHeader + kPanel + kGap) + kHeader; };
  const double axis_y = panel_top(panels - 1) + kPanel;
  const double height = axis_y + kBottom;
  const double duration = plan.duration_s > 0 ? plan.duration_s : 1.0;
  auto x_of = [&](double t) { return kLeft + t / duration * plot_w; };
  const double t_step = nice_step(duration, 10);

  std::string s;
  s += "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + fixed(kWidth, 0) + "\" height=\"" + fixed(height, 0) +
       "\" viewBox=\"0 0 " + fixed(kWidth, 0) + " " + fixed(height, 0) + "\" " + kFont + ">\n";
  s += "<rect x=\"0\" y=\"0\" width=\"" + fixed(kWidth, 0) + "\" height=\"" + fixed(height, 0) + "\" fill=\"#ffffff\"/>\n";
  // Homing spans: hatched, as the motor's speed there depends on where the switch is.
  s += "<defs><pattern id=\"homing\" width=\"6\" height=\"6\" patternUnits=\"userSpaceOnUse\" "
       "patternTransform=\"rotate(45)\"><rect width=\"6\" height=\"6\" fill=\"#f3f4f6\"/>"
       "<line x1=\"0\" y1=\"0\" x2=\"0\" y2=\"6\" stroke=\"#d0d4da\" stroke-width=\"2\"/></pattern></defs>\n";
  s += "<text x=\"" + fixed(kLeft, 0) + "\" y=\"28\" font-size=\"18\" font-weight=\"600\" fill=\"#1f2328\">" +
       escape(title) + "</text>\n";
  s += "<text x=\"" + fixed(kLeft, 0) + "\" y=\"46\" font-size=\"12\" fill=\"#656d76\">" +
       std::to_string(plan.actions.size()) + " actions, " + fixed(plan.duration_s, 3) +
       " s; velocity in steps/s; dashed: stage boundaries; numbers: actions</text>\n";

  // Action numbers above the first panel; actions starting too close together share a label
  // ("5-7"), and a label too close to the previous one is left out.
  double last_label = -1e9;
  for (size_t i = 0; i < plan.actions.size();) {
    const double x = x_of(plan.actions[i].start_s);
    size_t j = i + 1;
    while (j < plan.actions.size() && x_of(plan.actions[j].start_s) - x < kMinLabelGap / 2) ++j;
    const size_t first = plan.actions[i].index, last = plan.actions[j - 1].index;
    const std::string label = first == last ? std::to_string(first) : std::to_string(first) + "\u2013" + std::to_string(last);
    const double half = 3.2 * static_cast<double>(label.size());
    if (x - half - last_label >= 4) {
      last_label = x + half;
      s += "<text x=\"" + fixed(x) + "\" y=\"" + fixed(kTop - 6) + "\" font-size=\"10\" fill=\"#656d76\" "
           "text-anchor=\"middle\">" + label + "</text>\n";
    }
    i = j;
  }

  if (plan.tracks.empty()) {
    s += "<text x=\"" + fixed(kLeft + plot_w / 2) + "\" y=\"" + fixed(panel_top(0) + kPanel / 2) +
         "\" font-size=\"14\" fill=\"#656d76\" text-anchor=\"middle\">no motors</text>\n";
  }

  for (size_t p = 0; p < plan.tracks.size(); ++p) {
    const MotorTrack& track = plan.tracks[p];
    const char* colour = kColours[(track.motor + 2) % 3];
    const double top = panel_top(p);
    const double bottom = top + kPanel;

    double lo = 0, hi = 0;
    for (const VelocityPoint& v : track.velocity) {
      lo = std::min(lo, v.velocity);
      hi = std::max(hi, v.velocity);
    }
    const bool still = lo == hi;
    if (still) hi = 1;
    const double v_step = nice_step(hi - lo, 4);
    const double pad = (hi - lo) * 0.08;  // room above and below the curve
    lo -= pad;
    hi += pad;
    auto y_of = [&](double v) { return bottom - (v - lo) / (hi - lo) * kPanel; };

    s += "<g>\n";
    s += "<rect x=\"" + fixed(kLeft) + "\" y=\"" + fixed(top) + "\" width=\"" + fixed(plot_w) + "\" height=\"" +
         fixed(kPanel) + "\" fill=\"#fbfcfd\" stroke=\"#d0d7de\"/>\n";
    for (const Action& a : plan.actions) {
      if (a.kind != ActionKind::kHome) continue;
      if (std::find(a.motors.begin(), a.motors.end(), track.motor) == a.motors.end()) continue;
      const double x0 = x_of(a.start_s), x1 = x_of(a.end_s);
      s += "<rect x=\"" + fixed(x0) + "\" y=\"" + fixed(top + 1) + "\" width=\"" + fixed(std::max(1.0, x1 - x0)) +
           "\" height=\"" + fixed(kPanel - 2) + "\" fill=\"url(#homing)\"/>\n";
      s += "<text x=\"" + fixed((x0 + x1) / 2) + "\" y=\"" + fixed(bottom - 8) +
           "\" font-size=\"10\" fill=\"#8c959f\" text-anchor=\"middle\">homing</text>\n";
    }
    // Grid: velocity ticks, time ticks, action starts.
    for (double v = std::ceil(lo / v_step) * v_step; v <= hi; v += v_step) {
      const double y = y_of(v);
      const bool zero = std::fabs(v) < v_step * 1e-6;
      s += "<line x1=\"" + fixed(kLeft) + "\" y1=\"" + fixed(y) + "\" x2=\"" + fixed(kLeft + plot_w) + "\" y2=\"" +
           fixed(y) + "\" stroke=\"" + (zero ? "#8c959f" : "#eaeef2") + "\" stroke-width=\"1\"/>\n";
      s += "<text x=\"" + fixed(kLeft - 6) + "\" y=\"" + fixed(y + 4) + "\" font-size=\"11\" fill=\"#57606a\" "
           "text-anchor=\"end\">" + tick_label(v, v_step) + "</text>\n";
    }
    for (double t = 0; t <= duration + t_step * 1e-6; t += t_step) {
      s += "<line x1=\"" + fixed(x_of(t)) + "\" y1=\"" + fixed(top) + "\" x2=\"" + fixed(x_of(t)) + "\" y2=\"" +
           fixed(bottom) + "\" stroke=\"#eaeef2\" stroke-width=\"1\"/>\n";
    }
    double last_line = -1e9;
    for (const Action& a : plan.actions) {
      const double x = x_of(a.start_s);
      if (x - last_line < kMinLineGap) continue;
      last_line = x;
      s += "<line x1=\"" + fixed(x) + "\" y1=\"" + fixed(top) + "\" x2=\"" + fixed(x) + "\" y2=\"" + fixed(bottom) +
           "\" stroke=\"#c9d1d9\" stroke-width=\"0.8\"/>\n";
    }
    last_line = -1e9;
    for (double b : track.stage_boundaries_s) {
      const double x = x_of(b);
      if (x - last_line < kMinLineGap) continue;
      last_line = x;
      s += "<line x1=\"" + fixed(x) + "\" y1=\"" + fixed(top) + "\" x2=\"" + fixed(x) + "\" y2=\"" + fixed(bottom) +
           "\" stroke=\"" + colour + "\" stroke-opacity=\"0.45\" stroke-width=\"0.8\" stroke-dasharray=\"3,3\"/>\n";
    }
    // The velocity: a light area down to zero under the line.
    std::string points;
    for (const VelocityPoint& v : thinned(track.velocity, x_of)) {
      points += fixed(x_of(v.t_s), 2) + "," + fixed(y_of(v.velocity), 2) + " ";
    }
    if (!points.empty()) points.pop_back();
    const std::string zero_y = fixed(y_of(0), 2);
    if (!track.velocity.empty()) {
      s += "<polygon points=\"" + fixed(x_of(track.velocity.front().t_s), 2) + "," + zero_y + " " + points + " " +
           fixed(x_of(track.velocity.back().t_s), 2) + "," + zero_y + "\" fill=\"" + colour +
           "\" fill-opacity=\"0.12\" stroke=\"none\"/>\n";
    }
    s += "<polyline points=\"" + points + "\" fill=\"none\" stroke=\"" + colour +
         "\" stroke-width=\"1.6\" stroke-linejoin=\"round\"/>\n";
    // Labels: the motor, its microstep and where it goes.
    auto where = [](bool known, int64_t pos) { return known ? std::to_string(pos) : std::string("?"); };
    s += "<text x=\"" + fixed(kLeft) + "\" y=\"" + fixed(top - 6) + "\" font-size=\"13\" font-weight=\"600\" "
         "fill=\"" + colour + "\">" + escape(track.name) + " (motor " + std::to_string(track.motor) + ")</text>\n";
    s += "<text x=\"" + fixed(kLeft + plot_w) + "\" y=\"" + fixed(top - 6) + "\" font-size=\"11\" "
         "fill=\"#656d76\" text-anchor=\"end\">1/" + std::to_string(track.microstep) + " step, position " +
         where(track.start_known, track.start_position) + " \u2192 " + where(track.end_known, track.end_position) +
         (still ? ", at rest" : "") + "</text>\n";
    s += "<text transform=\"translate(" + fixed(16) + "," + fixed(top + kPanel / 2) + ") rotate(-90)\" "
         "font-size=\"11\" fill=\"#57606a\" text-anchor=\"middle\">steps/s</text>\n";
    s += "</g>\n";
  }

  // The shared time axis under the last panel.
  for (double t = 0; t <= duration + t_step * 1e-6; t += t_step) {
    s += "<line x1=\"" + fixed(x_of(t)) + "\" y1=\"" + fixed(axis_y) + "\" x2=\"" + fixed(x_of(t)) + "\" y2=\"" +
         fixed(axis_y + 5) + "\" stroke=\"#8c959f\"/>\n";
    s += "<text x=\"" + fixed(x_of(t)) + "\" y=\"" + fixed(axis_y + 18) + "\" font-size=\"11\" fill=\"#57606a\" "
         "text-anchor=\"middle\">" + tick_label(t, t_step) + "</text>\n";
  }
  s += "<text x=\"" + fixed(kLeft + plot_w / 2) + "\" y=\"" + fixed(axis_y + 40) +
       "\" font-size=\"12\" fill=\"#57606a\" text-anchor=\"middle\">time (s)</text>\n";
  s += "</svg>\n";
  return s;
}

std::string plot_csv(const Plan& plan) {
  std::string out = "t_s,motor,name,velocity\n";
  char buf[64];
  for (const MotorTrack& track : plan.tracks) {
    const std::string name = csv_field(track.name);
    for (const VelocityPoint& v : track.velocity) {
      std::snprintf(buf, sizeof buf, "%.6f,%u,", v.t_s, track.motor);
      out += buf;
      out += name;
      std::snprintf(buf, sizeof buf, ",%.3f\n", v.velocity);
      out += buf;
    }
  }
  return out;
}

}  // namespace hmc::motion
