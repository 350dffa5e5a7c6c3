#pragma once
// Feather files (docs/feather-format.md): strict JSON, versioned "pteryla_feather": 1. Unknown keys,
// missing fields, out-of-range numbers, NaN, rp outside [0,1] and key barbs with fewer than 2 control
// vertices are rejected with a pteryla::Error naming the file and the key path. save -> load is exact.
#include <string>

#include "pteryla/core/json.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/params.hpp"

namespace pteryla::feather {

inline constexpr int kFeatherFormatVersion = 1;

// Reads a feather definition from a JSON object (a whole file or one embedded in a scene). The
// "pteryla_feather" version key is optional here (must be 1 when present). Calls r.finish().
FeatherParams readFeather(JsonReader& r);
// JSON object for p, including "pteryla_feather": 1 when withVersion.
Json featherToJson(const FeatherParams& p, bool withVersion = true);

// Loads a feather file (version key required); sets FeatherParams::sourceFile.
FeatherParams loadFeather(const std::string& path);
void saveFeather(const std::string& path, const FeatherParams& p);

// Writes the shaft(s) and barbs as OBJ polylines ("l" elements), barbs sampled with barbSegments.
void writeCurvesObj(const std::string& path, const FeatherCurves& curves, int barbSegments = 8);

}  // namespace pteryla::feather
