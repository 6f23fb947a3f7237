#pragma once
// Shared by the core tests.
#include "core/check.hpp"

#include <functional>
#include <string>

namespace palpable::test {

// The message of the InputError `f` throws, or "accepted" if it throws none.
inline std::string input_error(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "accepted";
}

}  // namespace palpable::test
