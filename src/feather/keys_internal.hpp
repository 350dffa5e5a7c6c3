#pragma once
// Allocation-free helpers shared by params.cpp and barbs.cpp (not part of the public API).
#include <array>
#include <vector>

#include "pteryla/feather/params.hpp"

namespace pteryla::feather {

// effectiveKeyBarbs() writing into reusable storage.
void effectiveKeyBarbsInto(const FeatherParams& p, int vane, std::vector<KeyBarb>& keys);
void fillPlumulaceousBarb(uint64_t seed, glm::dvec3* cvs);  // 4 control vertices
std::array<glm::dvec3, 4> defaultPennaceousBarbArray();

}  // namespace pteryla::feather
