// Quantities with units, as people write them for an axis: "250mm", "-90deg", "1.5rev",
// "3200steps", "20mm/s", "100mm/s2". A quantity is a number, a length or angle unit, and how many
// times it is divided by seconds (0 a position or distance, 1 a speed, 2 an acceleration); the
// axis it is meant for (profile.h) turns it into steps.
#pragma once

#include <string>
#include <string_view>

#include "hmc/result.h"

namespace hmc {

enum class Unit : uint8_t {
  kMm,     // millimetres: linear axes
  kDeg,    // degrees: rotary axes
  kRev,    // turns of the axis's output (the pulley, the screw, the rotary stage)
  kSteps,  // motor steps at the axis's microstep, as `hmc move` counts them
};

// What a quantity measures: where (a position or distance), how fast, how quickly that changes.
enum class Dimension : uint8_t { kPosition = 0, kSpeed = 1, kAcceleration = 2 };

struct Quantity {
  double value = 0;
  Unit unit = Unit::kSteps;
  Dimension dimension = Dimension::kPosition;
};

// "mm", "deg", "rev", "steps".
const char* unit_name(Unit unit);
// "mm", "mm/s", "mm/s2".
std::string unit_text(Unit unit, Dimension dimension);
// "a position", "a speed", "an acceleration".
const char* dimension_words(Dimension dimension);

// Parses "250mm", "250 mm", "-90deg", "0.5rev", "3200steps" (also "step", "°", "turn"), "20mm/s",
// "100mm/s2", "100mm/s^2", "100mm/s²". The number is decimal (an exponent allowed); the unit is
// required. The error says what was expected.
Result<Quantity> parse_quantity(std::string_view text);

}  // namespace hmc
