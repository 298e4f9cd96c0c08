// Result<T, E>: a value or an error, returned instead of throwing across the library boundary.
#pragma once

#include <string>
#include <utility>
#include <variant>

namespace hmc {

// A plain error: what went wrong, in words a person can act on.
struct Error {
  std::string message;
};

template <typename T, typename E = Error>
class Result {
 public:
  Result(T value) : state_(std::in_place_index<0>, std::move(value)) {}  // NOLINT: implicit by design
  Result(E error) : state_(std::in_place_index<1>, std::move(error)) {}  // NOLINT: implicit by design
  // A default value made where it lies, to be filled in there: no copy of a value just written.
  explicit Result(std::in_place_t) : state_(std::in_place_index<0>) {}

  bool ok() const { return state_.index() == 0; }
  explicit operator bool() const { return ok(); }

  T& value() & { return std::get<0>(state_); }
  const T& value() const& { return std::get<0>(state_); }
  T&& value() && { return std::get<0>(std::move(state_)); }
  const E& error() const { return std::get<1>(state_); }

  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() { return value(); }
  const T& operator*() const { return value(); }

 private:
  std::variant<T, E> state_;
};

// The result of an operation that returns nothing but may fail.
struct Done {};
using Status = Result<Done>;

}  // namespace hmc
