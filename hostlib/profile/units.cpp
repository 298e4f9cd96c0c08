// Quantities with units: the text people write, read into a number, a unit and a dimension.
#include "hmc/units.h"

#include <charconv>
#include <cmath>

namespace hmc {
namespace {

bool starts_with(std::string_view text, std::string_view prefix) { return text.substr(0, prefix.size()) == prefix; }

// The unit names accepted, longest first so that "steps" is not read as "step" + "s".
struct UnitSpelling {
  std::string_view text;
  Unit unit;
};
constexpr UnitSpelling kSpellings[] = {
    {"steps", Unit::kSteps}, {"step", Unit::kSteps}, {"turns", Unit::kRev}, {"turn", Unit::kRev},
    {"revs", Unit::kRev},    {"rev", Unit::kRev},    {"deg", Unit::kDeg},   {"\xC2\xB0", Unit::kDeg},
    {"mm", Unit::kMm},
};

}  // namespace

const char* unit_name(Unit unit) {
  switch (unit) {
    case Unit::kMm: return "mm";
    case Unit::kDeg: return "deg";
    case Unit::kRev: return "rev";
    case Unit::kSteps: return "steps";
  }
  return "steps";
}

std::string unit_text(Unit unit, Dimension dimension) {
  std::string text = unit_name(unit);
  if (dimension == Dimension::kSpeed) text += "/s";
  if (dimension == Dimension::kAcceleration) text += "/s2";
  return text;
}

const char* dimension_words(Dimension dimension) {
  switch (dimension) {
    case Dimension::kPosition: return "a position or distance";
    case Dimension::kSpeed: return "a speed";
    case Dimension::kAcceleration: return "an acceleration";
  }
  return "a position or distance";
}

Result<Quantity> parse_quantity(std::string_view text) {
  const std::string shown(text);
  std::string_view rest = text;
  while (!rest.empty() && rest.front() == ' ') rest.remove_prefix(1);
  // from_chars takes no leading '+'; a sign is read here.
  double sign = 1;
  if (!rest.empty() && (rest.front() == '+' || rest.front() == '-')) {
    sign = rest.front() == '-' ? -1 : 1;
    rest.remove_prefix(1);
  }
  double number = 0;
  const auto [end, failure] = std::from_chars(rest.data(), rest.data() + rest.size(), number);
  if (failure != std::errc() || !std::isfinite(number)) {
    return Error{"'" + shown + "' is not a number with a unit (250mm, -90deg, 0.5rev, 3200steps, 20mm/s, 100mm/s2)"};
  }
  rest.remove_prefix(static_cast<size_t>(end - rest.data()));
  while (!rest.empty() && rest.front() == ' ') rest.remove_prefix(1);
  Quantity q;
  q.value = sign * number;
  bool known = false;
  for (const UnitSpelling& s : kSpellings) {
    if (starts_with(rest, s.text)) {
      q.unit = s.unit;
      rest.remove_prefix(s.text.size());
      known = true;
      break;
    }
  }
  if (!known) {
    return Error{"'" + shown + "' has " + (rest.empty() ? std::string("no unit") : "an unknown unit '" + std::string(rest) + "'") +
                 ": give mm, deg, rev or steps (and /s for a speed, /s2 for an acceleration)"};
  }
  if (starts_with(rest, "/s")) {
    rest.remove_prefix(2);
    q.dimension = Dimension::kSpeed;
    for (const std::string_view squared : {"2", "^2", "\xC2\xB2"}) {
      if (starts_with(rest, squared)) {
        rest.remove_prefix(squared.size());
        q.dimension = Dimension::kAcceleration;
        break;
      }
    }
  }
  if (!rest.empty()) {
    return Error{"'" + shown + "' has '" + std::string(rest) +
                 "' after its unit: write a speed as 20mm/s and an acceleration as 100mm/s2"};
  }
  return q;
}

}  // namespace hmc
