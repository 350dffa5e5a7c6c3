#pragma once
#include "pteryla/pipeline/pipeline.hpp"

namespace pteryla::pipeline {
// Fills the coat-level metrics (intersections, skin penetrations, coverage) of `m`.
void checkCoat(Pipeline& p, QualityMetrics& m);
}  // namespace pteryla::pipeline
