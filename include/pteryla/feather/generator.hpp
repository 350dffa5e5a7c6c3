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
#include "pteryla/feather/growth.hpp"
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
  // Grows the feather `def` to a growing state (featherAtState calls it only when !st.grown(); the
  // mature feather and wear stay the shared path). When empty, the derived Streit fields grow by the
  // staggered schedule (growth.hpp). The result is any valid FeatherParams (usually the Streit form).
  std::function<FeatherParams(const FeatherParams& def, const GrowthState& st, const GrowthSchedule& s)> grow;
};

// Adds or replaces a generator. "streit" is reserved.
void registerFeatherGenerator(const std::string& name, FeatherGenerator gen);
// nullptr when unknown (and for "streit").
const FeatherGenerator* findFeatherGenerator(const std::string& name);
std::vector<std::string> featherGeneratorNames();  // includes "streit"

// The feather in its Streit key-barb form: generator "streit", generatorParams dropped, every derived
// field kept (a generator's read hook derives the Streit fields when the file is read, so they are
// always current); the afterfeather likewise. A Streit feather is returned unchanged. blendFeathers
// blends feathers of different generators in this form.
FeatherParams streitForm(const FeatherParams& p);

}  // namespace pteryla::feather
