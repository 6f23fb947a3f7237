// keep_freed_heap (tools/lib/heap.hpp): a large block freed at the heap's top stays with the
// process for the next solve, instead of being unmapped and mapped again. Measured through the
// size of glibc's main heap (mallinfo2().arena, which a block in a mapping of its own does not
// count): with glibc's defaults an 8 MiB block is a mapping of its own and the heap does not
// grow.
#include "tools/lib/heap.hpp"

#include <catch2/catch.hpp>

#include <cstdlib>
#include <cstring>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

TEST_CASE("keep_freed_heap: a large block comes from the heap and stays there once freed") {
#if defined(__GLIBC__)
  palpable::tools::keep_freed_heap();
  constexpr std::size_t kBlock = std::size_t{8} << 20;
  const std::size_t before = mallinfo2().arena;
  char* volatile block = static_cast<char*>(std::malloc(kBlock));
  REQUIRE(block != nullptr);
  std::memset(block, 1, kBlock);
  const std::size_t during = mallinfo2().arena;
  std::free(block);
  const std::size_t after = mallinfo2().arena;
  CHECK(during >= before + kBlock);
  CHECK(after == during);
#else
  SUCCEED("not glibc: keep_freed_heap does nothing");
#endif
}
