#pragma once
// The coat's materials (CoatMesh::materials) and the material of every feather: one material per
// feather definition of the scene, in the scene's order, then one per distinct blend of key feathers'
// looks (issue #30 item 2, docs/feather-format.md "Material blending"). Internal to the pipeline; pure.
#include <cstdint>
#include <string>
#include <vector>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/key_feathers.hpp"
#include "pteryla/pipeline/pipeline.hpp"

namespace pteryla::pipeline {

// A feather definition's own material: texture paths resolved against the file it came from.
CoatMaterial definitionMaterial(const std::string& name, const feather::FeatherParams& p);

struct CoatMaterials {
  std::vector<CoatMaterial> materials;
  std::vector<uint32_t> featherMaterial;  // per feather of the coat: index into `materials`
};

// `names`: the scene's feather definitions (the library's keys) in the scene's order; they are
// materials 0..names.size()-1. A feather made from one key feather, or whose key feathers all look the
// same (sameLook), or whose quantised weight is all on one look, gets the material of its definition
// name (FeatherParams::name: the heaviest key), exactly as an unblended feather. Any other feather gets
// the blend of its key feathers' looks by its geometry's weights quantised to 1/kMaterialWeightSteps
// (largest remainder, so they still sum to 1); feathers with the same looks and quantised weights share
// one material, appended in feather order, named after the first such feather's keys ("a 3/8 + b 5/8";
// a part stands for every definition with its look). Depends only on the rest coat, never on the time.
CoatMaterials coatMaterials(const std::vector<std::string>& names, const coat::FeatherLibrary& library,
                            const coat::CoatFeathers& coat);

// Weights (normalised, >= 0) quantised to multiples of 1/steps that sum to exactly `steps`: each gets
// floor(w x steps), and the remaining steps go to the largest remainders (ties: the lower index).
std::vector<int> quantiseWeights(const std::vector<double>& weights, int steps);

}  // namespace pteryla::pipeline
