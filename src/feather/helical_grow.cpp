// Helical feathers in a growing coat: Zhang & Kanai's helical growth (4.1) and unfurling (4.2) played on
// the stages of a Streit growth schedule (Streit 2003, 8.1, Fig. 8.1). The collar growth takes the
// shaft and barb growth windows, unfurling takes the opening window, and the last (open) stage turns
// the unfurled barbs into the feather's own key barbs while the rachis curves. docs/growth.md.
#include <algorithm>
#include <memory>
#include <mutex>
#include <utility>

#include "pteryla/core/error.hpp"
#include "pteryla/feather/generator.hpp"
#include "pteryla/feather/helical.hpp"
#include "pteryla/feather/interpolate.hpp"

namespace pteryla::feather {

namespace {

// Growth schedules (travel-time tables, spawn schedule) of the last few helical parameter sets: every
// growing feather of a tract shares its key feather's parameters, and a coat asks for them each frame.
// The cache only saves work; a HelicalGrowth is a pure function of its parameters.
class GrowthCache {
 public:
  std::shared_ptr<const HelicalGrowth> get(const Json& params, const std::string& file) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& e : entries_)
      if (e.first == params) return e.second;
    JsonReader r(params, file, "helical");
    auto g = std::make_shared<const HelicalGrowth>(readHelical(r), file);
    if (entries_.size() >= kEntries) entries_.erase(entries_.begin());
    entries_.emplace_back(params, g);
    return g;
  }

 private:
  static constexpr size_t kEntries = 16;
  std::mutex mutex_;
  std::vector<std::pair<Json, std::shared_ptr<const HelicalGrowth>>> entries_;
};

GrowthCache& growthCache() {
  static GrowthCache* cache = new GrowthCache;  // never destroyed: used from worker threads at exit
  return *cache;
}

}  // namespace

HelicalGrowthStage helicalGrowthStage(const GrowthState& st, const HelicalParams& hp) {
  HelicalGrowthStage s;
  s.collar = 0.5 * (st[GrowthParam::ShaftLength] + st[GrowthParam::BarbLength]);
  s.unfurlLeft = hp.unfurlLeft * st[GrowthParam::Opening];
  s.unfurlRight = hp.unfurlRight * st[GrowthParam::Opening];
  s.open = st[GrowthParam::KeyBarbs];
  s.curvature = st[GrowthParam::RachisCurvature];
  return s;
}

FeatherParams growHelical(const FeatherParams& def, const GrowthState& st, const GrowthSchedule& sched) {
  if (!def.generatorParams.is_object())
    throw Error("helical feather has no helical parameters", def.sourceFile, "helical");
  const std::shared_ptr<const HelicalGrowth> g = growthCache().get(def.generatorParams, def.sourceFile);
  const HelicalParams& hp = g->params();
  const HelicalGrowthStage stage = helicalGrowthStage(st, hp);
  const double tEnd = g->endTime();
  const double collar = std::max(stage.collar, kMinGrowthScale);
  // The growing feather keeps the mature feather's scale (output units per growth unit), so its rachis
  // is the grown height v_grow t scaled like the mature one: def.rachisLength at the end of growth.
  const double scale = def.rachisLength / (hp.growthSpeed * tEnd);
  const HelicalFeather hf = helicalFeatherAt(*g, collar * tEnd, stage.unfurlLeft, stage.unfurlRight);
  HelicalConversion c = convertHelicalScaled(*g, hf, scale);

  FeatherParams p = streitForm(def);
  p.afterfeather = nullptr;
  adoptConvertedBarbs(p, std::move(c));
  p.calamusLength = def.calamusLength * collar;
  p.rachisWidth = def.rachisWidth * st[GrowthParam::ShaftWidth];
  // The rachis is straight while the feather grows (8.3: a pin feather is stiff) and curves in the open
  // stage, as a Streit feather's does.
  p.rachisLateralCurvature *= stage.curvature;
  p.rachisVentralDorsalCurvature *= stage.curvature;
  p.splits.openingAngle *= stage.curvature;
  if (stage.open > 0) {
    // The open stage: the unfurled barbs become the feather's own key barbs (the same shapes for a
    // feather read from its file; a blended coat feather's blended ones).
    FeatherParams own = streitForm(def);
    own.afterfeather = nullptr;
    own.rachisLateralCurvature = p.rachisLateralCurvature;
    own.rachisVentralDorsalCurvature = p.rachisVentralDorsalCurvature;
    own.splits.openingAngle = p.splits.openingAngle;
    own.rachisWidth = p.rachisWidth;
    p = stage.open >= 1 ? std::move(own) : blendFeathers({&p, &own}, {1 - stage.open, stage.open});
  }
  if (def.afterfeather)
    p.afterfeather = std::make_shared<const FeatherParams>(featherAtState(*def.afterfeather, st, sched));
  return p;
}

}  // namespace pteryla::feather
