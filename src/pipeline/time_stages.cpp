// Interim time stages: rest pose, mature coat, no controls. Replaced as src/moult lands.
#include "time_stages.hpp"

namespace pteryla::pipeline {

void poseSkin(const Scene&, double, const coat::SkinMesh&, coat::SkinMesh&, TimeState&) {}
void featherAges(const Scene&, double, const std::vector<coat::TractParameterization>&, const coat::Follicles&,
                 TimeState&, coat::CoatFeathers&) {}
void applyControls(const Scene&, double, const coat::SkinMesh&, const coat::Follicles&, TimeState&,
                   coat::CoatFeathers&, std::vector<double>&) {}

}  // namespace pteryla::pipeline
