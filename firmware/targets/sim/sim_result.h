// Result<T>: a value, or the message saying why there is none. hmc-sim's parsers and
// endpoint constructors return these instead of throwing.
#pragma once

#include <optional>
#include <string>
#include <utility>

namespace hmc::sim {

template <typename T>
struct Result {
  std::optional<T> value;
  std::string error;  // set exactly when value is empty

  static Result ok(T v) { return Result{std::optional<T>(std::move(v)), {}}; }
  static Result fail(std::string message) { return Result{std::nullopt, std::move(message)}; }
  explicit operator bool() const { return value.has_value(); }
};

}  // namespace hmc::sim
