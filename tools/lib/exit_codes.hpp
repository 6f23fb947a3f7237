#pragma once
// Exit codes of the `palpable` command line, documented in `palpable --help` and the README.
namespace palpable::tools {
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;      // the run itself failed (numerical failure, I/O error)
inline constexpr int kExitBadInput = 2;     // bad command line, scene or spec: nothing was run
inline constexpr int kExitCheckFailed = 3;  // ran, but a comparison asked for did not hold
inline constexpr int kExitStopped = 4;      // ran, but stopped at its CPU budget before its end
}  // namespace palpable::tools
