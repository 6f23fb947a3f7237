// libFuzzer target: the scene loader. Any bytes are parsed as a scene file; bad input must be an
// InputError (exit 2 on the command line), never a crash, a sanitizer report or another
// exception. Built with -DPALPABLE_FUZZ=ON (clang); see tests/fuzz/README.md.
#include "core/check.hpp"
#include "scenarios/json_reader.hpp"
#include "scenarios/scene.hpp"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const nlohmann::json doc = palpable::parse_json_text(text, "fuzz.json");
    palpable::scene_from_json(doc, "fuzz.json");
  } catch (const palpable::InputError&) {
    // Bad input, named: the promise kept.
  }
  return 0;
}
