#pragma once
// Errors in tiers (STYLE.md):
//  - PALPABLE_CHECK: an always-on check of a broken invariant (a bug), throws InvariantError;
//  - PALPABLE_DCHECK: the same, compiled only in checked builds (-DPALPABLE_CHECKED=ON);
//  - InputError: bad input at a boundary (scene file, command line, public constructor), with the
//    JSON path or argument name it concerns and what was expected;
//  - numerical trouble inside algorithms is a status in the result and a counter, never a throw.
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <string>

namespace palpable {

class InvariantError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

class InputError : public std::runtime_error {
 public:
  // `where`: a JSON pointer ("/bodies/0/mass"), an argument name, or a file name.
  InputError(std::string where, const std::string& message)
      : std::runtime_error(where.empty() ? message : where + ": " + message),
        where_(std::move(where)) {}
  const std::string& where() const { return where_; }

 private:
  std::string where_;
};

// A number for a message, with the digits that matter (std::to_string prints 1e-9 as 0.000000).
inline std::string significant(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", x);
  return buffer;
}

namespace detail {
[[noreturn]] inline void check_failed(const char* condition, const char* file, int line,
                                      const std::string& message) {
  std::ostringstream os;
  os << file << ":" << line << ": invariant violated: " << condition;
  if (!message.empty()) os << " (" << message << ")";
  throw InvariantError(os.str());
}
}  // namespace detail

}  // namespace palpable

#define PALPABLE_CHECK(condition, message)                                         \
  do {                                                                             \
    if (!(condition)) ::palpable::detail::check_failed(#condition, __FILE__, __LINE__, \
                                                       (message));                 \
  } while (false)

#ifdef PALPABLE_CHECKED
#define PALPABLE_DCHECK(condition, message) PALPABLE_CHECK(condition, message)
#else
#define PALPABLE_DCHECK(condition, message) \
  do {                                      \
  } while (false)
#endif
