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
// validateFeather() for a feather read at JSON key path `path` (element names get that prefix).
void validateFeatherAt(const FeatherParams& p, const std::string& file, const std::string& path);

}  // namespace pteryla::feather
