#pragma once
// FNV-1a, 64 bits (Fowler, Noll, Vo) of some bytes, as 16 hex digits: a fingerprint that is the
// same on every platform (sweep fingerprints, the scene hash in a run's provenance).
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

namespace palpable::tools {

inline std::string fnv1a64_hex(std::string_view bytes) {
  std::uint64_t hash = 14695981039346656037ull;
  for (unsigned char c : bytes) {
    hash ^= c;
    hash *= 1099511628211ull;
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(hash));
  return hex;
}

}  // namespace palpable::tools
