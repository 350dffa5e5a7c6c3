#pragma once
// Scene edits shared by the panels and the script runner, so a scripted session exercises exactly what
// the panels do. Each is one Document::edit (one undo step; repeated calls with the same target inside
// a gesture merge). Sections are edited as JSON in the formats of docs/scene-format.md and the module
// docs; docs/viewer.md lists what the viewer writes.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "document.hpp"
#include "pteryla/feather/params.hpp"

namespace pteryla::viewer::actions {

// Tracts and follicles. `tract` indexes scene().tracts (an empty list first becomes [{"name": "all"}]).
void ensureTracts(Document& d);
void setTractCount(Document& d, size_t tract, size_t count);                                // exact follicle count
void setTractDensity(Document& d, size_t tract, double density);                            // follicles per unit area
void setRelaxIterations(Document& d, size_t tract, int iterations);                         // 0 = scattered only
void setRelaxNumber(Document& d, size_t tract, const std::string& key, const Json& value);  // relax.<key>
void addBias(Document& d, size_t tract, const glm::dvec3& at, const glm::dvec3& direction, double sigma, double stretch,
             double densityGain = 0);
void addPinned(Document& d, size_t tract, const glm::dvec3& at);
// A new tract from mesh groups (names of SkinMesh::groupNames).
void addTract(Document& d, const std::string& name, const std::vector<std::string>& groups);
void removeTract(Document& d, size_t tract);
// Painting tract faces (source polygons, docs/tracts.md; `rest`: the rest skin, Snapshot::restSkin).
// The faces a tract's selection gives, sorted.
std::vector<uint32_t> tractSourceFaces(const pipeline::Scene& s, const coat::SkinMesh& rest, size_t tract);
// Adds or removes faces. Adding to a tract built only from additive selectors (groups, faces, labels,
// union) appends the new faces to its `faces` list and keeps the rest; otherwise (removing, or a tract
// with intersect / subtract / no selector) the tract's selection becomes the explicit face list it now
// selects. False (and no edit) when the tract does not change; an error when it would lose every face.
bool paintTractFaces(Document& d, const coat::SkinMesh& rest, size_t tract, const std::vector<uint32_t>& faces,
                     bool add);
// A new tract of these source faces (the face selection painted in the view); with several feathers in
// the library it carries the first (by name).
void addTractFromFaces(Document& d, const std::string& name, const std::vector<uint32_t>& faces);

// The painted follicle density (scene density_map, one factor per rest-skin vertex): stored rounded to
// 1/1000 (paint.hpp); clearing removes the map from the scene (its side file stays on disk).
void setDensityFactors(Document& d, std::vector<float> factors);
void clearDensityMap(Document& d);

// Feathers: a feather name mapped to a file (absolute or relative to the working directory) or an
// inline definition (the designer's result).
void setFeatherFile(Document& d, const std::string& name, const std::string& path);
void setFeatherInline(Document& d, const std::string& name, const feather::FeatherParams& p);
void setTractFeather(Document& d, size_t tract, const std::string& feather);  // tract default feather
void addKeyFeather(Document& d, size_t tract, const std::string& feather, uint64_t follicleId);
void addKeyFeatherAt(Document& d, size_t tract, const std::string& feather, const glm::dvec3& at);
void removeKeyFeather(Document& d, size_t tract, size_t key);

// The scene's render.lod (renders, the CLI), as an undoable edit; the viewer's preview level of detail
// (Document::setLod) is separate and never saved.
void setRenderLod(Document& d, double fraction);
// render.instance_tolerance in [0, 0.1] (0 = off): feathers that close share one unplaced mesh; only the
// mesh stage re-runs.
void setInstanceTolerance(Document& d, double fraction);

// Directions: a styling vector over a body axis combs it locally (the axis is kept; coat/directions.hpp)
// within `radius` (0: the field's falloff, else combRadius() of the axis); without an axis, styling
// vectors are the whole field. A new axis keeps the comb strokes (the vectors over the old axis) and
// replaces a vectors-only field.
void addStylingVector(Document& d, const glm::dvec3& at, const glm::dvec3& direction, double radius = 0);
// Default reach of a comb stroke: a tenth of the scene's body axis length (0 without an axis).
double combRadius(const pipeline::Scene& s);
void setStylingVector(Document& d, size_t k, const glm::dvec3& at, const glm::dvec3& direction);
void removeStylingVector(Document& d, size_t k);
void setBodyAxis(Document& d, const std::vector<glm::dvec3>& points);

// Packing: a fixed-angle brush (packing.styling sphere selection).
// `lift`: the feathers under it stand at least elevationDeg (min_elevation_deg: a lift brush); else they
// are set to it (elevation_deg: raised or flattened to that angle).
void addBrush(Document& d, const glm::dvec3& center, double radius, double elevationDeg, bool lift = false);
void removeBrush(Document& d, size_t k);
void setPackingValue(Document& d, const std::string& key, const Json& value);

// Expressive controls (AnimFur, Grier 2019; schema in docs/controls.md, moult/controls.hpp): a control
// at a point with a radius of influence and the behaviour weights lift / aim / direction / random /
// dynamic in [0, 1], each a constant or keyframed ("keys": [{"t", "lift", ...}]).
inline const char* const kControlBehaviours[] = {"lift", "aim", "direction", "random", "dynamic"};
size_t addControl(Document& d, const glm::dvec3& at, double radius);
// A keyed behaviour gets (or updates) a key at `time`; an unkeyed one is set as a constant.
void setControlValue(Document& d, size_t control, const std::string& behaviour, double value, double time);
void setControlPoint(Document& d, size_t control, const glm::dvec3& at, double radius);
// Keys every behaviour at `time` with its current value there (constants become keys).
void addControlKeyframe(Document& d, size_t control, double time);
void removeControlKeyframe(Document& d, size_t control, size_t key);
void removeControl(Document& d, size_t control);
// Behaviour values of control `c` at time t as the moult module evaluates them (0 when unreadable).
struct ControlNow {
  double value[5] = {0, 0, 0, 0, 0};
  bool keyed[5] = {false, false, false, false, false};
};
ControlNow controlAt(const pipeline::Scene& s, size_t control, double time);

// Render settings (no re-evaluation).
void setStyle(Document& d, const std::string& style);
void setBrdf(Document& d, double dSpacing, double hFloor);

// JSON helpers.
Json vec3Json(const glm::dvec3& v);
// Whether a control's keys set `attribute` anywhere; the control's key at exactly `time`, made (and the
// keys sorted by time, equal times in their order) when there is none.
bool controlKeyedIn(const Json& ctl, const std::string& attribute);
Json& controlKeyAt(Json& ctl, double time);
glm::dvec3 jsonVec3(const Json& j, const glm::dvec3& def = glm::dvec3(0));

}  // namespace pteryla::viewer::actions
