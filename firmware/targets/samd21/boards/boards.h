// Every board variant, and the lookup by name that board.h and the build use. Add a variant:
// a header beside this one with its table, listed in kVariants below.
#pragma once

#include "bench.h"
#include "seed.h"
#include "../pin_map.h"

namespace hmc::samd21::boards {

inline constexpr const pin_map::BoardVariant* kVariants[] = {&kSeed, &kBench};
inline constexpr const char* kDefaultVariant = "seed";

constexpr bool has_variant(const char* name) {
  for (const pin_map::BoardVariant* v : kVariants) {
    if (pin_map::same_text(v->name, name)) return true;
  }
  return false;
}

// The variant called `name`, or nullptr.
constexpr const pin_map::BoardVariant* find_variant(const char* name) {
  for (const pin_map::BoardVariant* v : kVariants) {
    if (pin_map::same_text(v->name, name)) return v;
  }
  return nullptr;
}

}  // namespace hmc::samd21::boards
