// The independent coat checker as used by `pteryla check` (interim: follicle metrics only).
#include "pipeline_internal.hpp"

namespace pteryla::pipeline {

void checkCoat(Pipeline&, QualityMetrics&) {}

}  // namespace pteryla::pipeline
