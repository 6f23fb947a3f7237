// A deliberately wrong file: impulse must never use distance (DESIGN.md §1). The layering check
// must reject this tree; see tests/CMakeLists.txt.
#include "distance/closest_features.hpp"
