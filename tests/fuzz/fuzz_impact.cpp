// libFuzzer target: the impact spec (palpable impact). Any bytes are parsed as a spec; a valid one
// is resolved. Bad input must be an InputError, resolving must not throw.
#include "core/check.hpp"
#include "tools/lib/impact_spec.hpp"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  palpable::tools::ImpactSpec spec;
  try {
    spec = palpable::tools::parse_impact_spec_text(text, "fuzz.json");
  } catch (const palpable::InputError&) {
    return 0;
  }
  palpable::tools::resolve_impact(spec);  // never throws: trouble is the result's status
  return 0;
}
