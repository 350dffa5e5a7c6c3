#pragma once
// The wing of thesis Fig. 8.6 as an in-memory scene for the moult module's pipeline tests: coverts on
// top, remiges along the trailing edge, packed with height fields. Paths are relative to data/scenes.
#include "pteryla/core/json.hpp"

namespace moult_test {

inline pteryla::Json wingScene() {
  return pteryla::Json::parse(R"({
    "pteryla": 1,
    "seed": 5,
    "mesh": "../meshes/wing.obj",
    "feathers": {"contour": "../feathers/contour.json"},
    "tracts": [
      {"name": "coverts", "groups": ["coverts"], "count": 90, "feather_scale": "auto",
       "feather_spacings": 1.5, "relax": {"iterations": 5}},
      {"name": "remiges", "groups": ["remiges_base"], "count": 40, "feather_scale": "auto",
       "feather_spacings": 1.5, "relax": {"iterations": 5}}
    ],
    "directions": {"axis": [[0, 0, -0.2], [2, 0, 0.4]]},
    "packing": {"method": "height_field"}
  })");
}

}  // namespace moult_test
