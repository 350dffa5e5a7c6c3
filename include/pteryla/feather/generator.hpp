#pragma once
// Feather generators: "streit" (built in, Streit 2003 5.2.2) builds barbs by key-barb interpolation.
// Other generators (e.g. "helical", Zhang & Kanai) register hooks by name; a feather file selects one
// with "generator": "<name>". Static libraries drop unreferenced registrar objects, so register
// explicitly: builtin generators are registered inside registerBuiltinFeatherGenerators()
// (src/feather/generator.cpp), which the registry runs once on first use. The Table 5.1 fields stay
// required for every generator (shaft, spacing and angles are shared); a generator adds its own keys.
#include <functional>
#include <string>
#include <vector>

#include "pteryla/core/json.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/params.hpp"

namespace pteryla::feather {

struct FeatherGenerator {
  // Reads the generator's own keys from the feather object into p.generatorParams (mark them used
  // through the reader; unknown keys are still rejected afterwards). Required.
  std::function<void(JsonReader& r, FeatherParams& p)> read;
  // Writes p.generatorParams back into the feather object `j`. Required.
  std::function<void(const FeatherParams& p, Json& j)> write;
  // Builds the curves; when empty the Streit barb generator is used.
  std::function<void(const FeatherParams& p, FeatherCurves& out, const GenerateOptions& opt)> generate;
  // Blends generatorParams of feathers (same generator) with normalized weights; when empty the
  // generatorParams of the heaviest feather are kept.
  std::function<Json(const std::vector<const FeatherParams*>& fs, const std::vector<double>& w)> blend;
};

// Adds or replaces a generator. "streit" is reserved.
void registerFeatherGenerator(const std::string& name, FeatherGenerator gen);
// nullptr when unknown (and for "streit").
const FeatherGenerator* findFeatherGenerator(const std::string& name);
std::vector<std::string> featherGeneratorNames();  // includes "streit"

}  // namespace pteryla::feather
