#pragma once
// Helical feather growth after Zhang & Kanai, "Biological Modeling of Feather Based on Morphogenesis"
// (section 4): barb ridges grow helically on the follicle collar and unfurl as the feather leaves the
// sheath. The result is converted into an ordinary FeatherParams (key barbs + silhouette), so a helical
// feather meshes, packs, moults and renders like any Streit feather. File format: docs/helical.md.
//
// Concepts
//  - Collar C(s), s in [0,1) the arc-length fraction, a closed counter-clockwise curve in the collar
//    plane; C(0) is the anterior polar where the rachial ridge forms. "Follicle space" is (x, y, z) =
//    (C.x, height, C.y): the feather grows along +y out of the collar plane y = 0.
//  - Anterior interval I_A = [anteriorLeft, 1) u [0, anteriorRight] (the rachial ridge) and posterior
//    interval I_P = [posteriorRight, posteriorLeft] (the barb generative zone). Left vane loci lie in
//    (posteriorLeft, anteriorLeft), right vane loci in (anteriorRight, posteriorRight).
//  - Emitters E_l, E_r start at I_A and move toward I_P with speed V_e(s) (locus units per time unit),
//    clamped when they reach I_P; they spawn barb tips (eqs. 1-3). Every barb tip then travels back
//    toward I_A with speed V_b(s) and its trail is the barb (Algorithm 1: the emitter moves by -V_e,
//    the barb by +V_b on the left side); the barb is complete when it reaches I_A, where it fuses with
//    the rachial ridge. A trail point recorded at time stamp t sits at height v_grow (t_now - t) (eq. 4).
//    The paper's text says the barb stops at I_P; that contradicts its Algorithm 1 and the biology
//    (barbs fuse into the rachis at the anterior), so the anterior reading is implemented.
//  - The emulation stops when N barbs (both vanes) are complete; developing barbs are discarded.
//  - Unfurling (4.2): each barb segment is rotated about the collar binormal (the follicle axis, since
//    the collar is planar) from the distal end to the proximal end so that it turns toward the
//    direction of the next proximal segment, by the fraction w of the full alignment angle. w = 1
//    flattens a vane into the plane of the rachis; w = 0 leaves it on the collar cylinder.
//
// Exactness: emitter and barb motion is integrated through tabulated travel-time functions (cubic
// Hermite with exact derivatives 1/V), spawn times are exact (i/f, or equal trail length), and barbs are
// sampled on a per-barb time grid independent of the animation step, so stepping with any dt gives the
// same barbs.
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "pteryla/core/json.hpp"
#include "pteryla/feather/generator.hpp"
#include "pteryla/feather/growth.hpp"
#include "pteryla/feather/params.hpp"

namespace pteryla::feather {

// ---------------------------------------------------------------------------------------------------
// Curve1D: an editable 1D curve (like a DCC curve widget): key points (x, y) with strictly increasing x,
// interpolated by a monotone cubic Hermite spline (Fritsch-Carlson), so the curve never overshoots its
// keys; constant beyond the first and last key. JSON form: [[x, y], ...].
class Curve1D {
 public:
  Curve1D() = default;                             // empty: evaluates to 0
  explicit Curve1D(std::vector<glm::dvec2> keys);  // throws Error for unsorted / non-finite keys
  static Curve1D constant(double y) { return Curve1D({{0.0, y}}); }

  const std::vector<glm::dvec2>& keys() const { return keys_; }
  void setKeys(std::vector<glm::dvec2> keys);  // validates and recomputes tangents
  bool empty() const { return keys_.empty(); }
  double operator()(double x) const;
  // Extremes over all x (the spline stays within its keys' range).
  double minValue() const;
  double maxValue() const;

  bool operator==(const Curve1D& o) const { return keys_ == o.keys_; }
  bool operator!=(const Curve1D& o) const { return !(*this == o); }

 private:
  std::vector<glm::dvec2> keys_;
  std::vector<double> slopes_;
};

Json curveToJson(const Curve1D& c);
// Throws Error(file, path) for a malformed array, fewer than 1 key, non-finite or unsorted x.
Curve1D curveFromJson(const Json& j, const std::string& file, const std::string& path);

// ---------------------------------------------------------------------------------------------------
// Collar shape: a circle, or a closed composite cubic Bezier of K segments given by 3K control points
// (segment k: P[3k], P[3k+1], P[3k+2], P[3k+3 mod 3K]). Must run counter-clockwise; s = 0 is P[0] (or
// the point (radius, 0) of the circle).
struct CollarShape {
  enum class Kind { Circle, Bezier };
  Kind kind = Kind::Circle;
  double radius = 1.5;             // scene units (circle)
  std::vector<glm::dvec2> points;  // Bezier control points, collar plane, scene units
  bool operator==(const CollarShape& o) const { return kind == o.kind && radius == o.radius && points == o.points; }
};

// Arc-length parameterized collar: s is the fraction of the perimeter from C(0), wrapped into [0,1).
class Collar {
 public:
  explicit Collar(const CollarShape& shape, const std::string& file = {});  // throws Error
  double length() const { return length_; }
  glm::dvec2 point(double s) const;
  glm::dvec2 tangent(double s) const;        // unit, direction of increasing s
  glm::dvec2 outwardNormal(double s) const;  // unit, away from the follicle centre

 private:
  glm::dvec2 evalU(double u, glm::dvec2* d) const;  // composite parameter u in [0, K)
  double uOfS(double s) const;
  CollarShape shape_;
  double length_ = 0;
  std::vector<double> tableU_, tableS_, tableD_;  // arc-length table (u, s, ds/du) for Bezier collars
};

// ---------------------------------------------------------------------------------------------------
enum class SpawnMode {
  Time,       // the paper: one barb per emitter every 1/f time units
  ArcLength,  // one barb per emitter every v_grow / f of emitter trail length on the collar cylinder
};

struct HelicalParams {
  CollarShape collar;
  // Loci on the collar, 0 < anteriorRight < posteriorRight < posteriorLeft < anteriorLeft < 1.
  double anteriorLeft = 0.99, anteriorRight = 0.01;
  double posteriorLeft = 0.51, posteriorRight = 0.49;
  double frequency = 2.0;                          // f: barbs per emitter per time unit
  double growthSpeed = 0.1;                        // v_grow: scene units per time unit
  Curve1D emitterSpeed = Curve1D::constant(0.05);  // V_e(s): locus units per time unit, > 0
  Curve1D barbSpeed = Curve1D::constant(0.05);     // V_b(s): locus units per time unit, > 0
  // Speed curves are defined over s in [0,1]; when true they are evaluated at a warped locus that maps
  // the posterior polar to 0.5 (Fig. 7: the curves' lowest point follows the polar).
  bool syncSpeedToPolar = true;
  int barbCount = 120;  // N: completed barbs over both vanes
  SpawnMode spawnMode = SpawnMode::Time;
  double sampleDt = 0.05;   // time between recorded barb points (Algorithm 1's time step)
  double unfurlLeft = 1.0;  // w per vane, [0,1]
  double unfurlRight = 1.0;
  // Conversion to FeatherParams.
  double length = 0;               // scale so the rachis is this long (scene units); 0: the feather file's
                                   // rachis.length (applyHelical) or the grown length v_grow t_end
  int fitCvs = 4;                  // control vertices per fitted barb Bezier, [2, 8]
  double keyBarbTolerance = 0.01;  // key barbs are added until interpolation error < this (unit chord)
  int maxKeyBarbs = 40;            // per vane, >= 2

  double posteriorPolar() const { return 0.5 * (posteriorLeft + posteriorRight); }
  void setPosteriorPolar(double s, double halfWidth = 0.01) {
    posteriorLeft = s + halfWidth;
    posteriorRight = s - halfWidth;
  }
  bool operator==(const HelicalParams& o) const;
  bool operator!=(const HelicalParams& o) const { return !(*this == o); }
};

// Throws Error (element = JSON-style key) for unusable values: interval order, non-positive speeds,
// frequencies, counts out of range, collar not counter-clockwise, ...
void validateHelical(const HelicalParams& p, const std::string& file = {});
// Reads the body of a "helical" object (calls r.finish()).
HelicalParams readHelical(JsonReader& r);
Json helicalToJson(const HelicalParams& p);

// ---------------------------------------------------------------------------------------------------
// One spawned barb. Vanes: 0 left, 1 right (as FeatherParams::vane).
struct HelicalBarb {
  uint8_t vane = 0;
  uint32_t index = 0;         // spawn index on its vane, from 1
  double spawnTime = 0;       // t_i
  double spawnLocus = 0;      // s of the barb tip (its distal end)
  double completionTime = 0;  // when the barb reaches I_A
  bool tipRegion = false;     // spawned while the emitter was still moving (the feather tip)
};

namespace detail {
// Monotone travel-time function F(sigma) = integral_0^sigma g, tabulated on a uniform grid with exact
// slopes g (cubic Hermite); the inverse is the Hermite interpolant of the swapped nodes.
struct TravelTable {
  double span = 0, h = 0;
  std::vector<double> value, slope;
  double operator()(double sigma) const;
  double inverse(double f) const;
  double total() const { return value.empty() ? 0.0 : value.back(); }
};
}  // namespace detail

// The growth schedule of a parameter set: travel-time tables, spawn schedule, end time. Immutable and
// cheap to query at any time; evaluation at time t needs no stepping.
class HelicalGrowth {
 public:
  explicit HelicalGrowth(const HelicalParams& p, const std::string& file = {});  // validates

  const HelicalParams& params() const { return p_; }
  const Collar& collar() const { return collar_; }
  double endTime() const { return endTime_; }
  // Every barb spawned before endTime(), per vane in spawn order (left vane first).
  const std::vector<HelicalBarb>& barbs() const { return barbs_; }
  // barbs()[vaneBegin(v) .. vaneBegin(v + 1)) belong to vane v.
  size_t vaneBegin(int v) const { return vaneBegin_[v]; }
  size_t completedCount() const { return completed_; }
  bool completed(const HelicalBarb& b) const { return b.completionTime <= endTime_; }
  double clampTime(int vane) const;  // when emitter `vane` reaches I_P

  double emitterLocus(int vane, double t) const;
  // Locus of barb b's trail point recorded tau time units after its spawn (clamped to its completion).
  double barbLocus(const HelicalBarb& b, double tau) const;
  // Time stamps of the recorded trail points of b up to time t (<= completion): a fixed grid
  // spawnTime + k sampleDt, plus min(t, completionTime) itself.
  void barbStamps(const HelicalBarb& b, double t, std::vector<double>& stamps) const;
  size_t maxStampCount(const HelicalBarb& b) const;

  // Follicle-space position (C.x, height, C.y) of a trail point with locus s and stamp at time t.
  glm::dvec3 folliclePoint(double s, double stamp, double t) const;
  // Distance travelled from I_A along the collar (locus units) <-> locus, per vane.
  double locusOf(int vane, double sigma) const;
  double sigmaOf(int vane, double s) const;
  double span(int vane) const;  // |I_A boundary - I_P boundary| in locus units

 private:
  double speedArg(double s) const;
  HelicalBarb spawn(int vane, uint32_t i) const;
  HelicalParams p_;
  Collar collar_;
  detail::TravelTable emit_[2], barb_[2], trail_[2];  // trail_: emitter trail length (ArcLength mode)
  std::vector<HelicalBarb> barbs_;
  size_t vaneBegin_[3] = {0, 0, 0};
  size_t completed_ = 0;
  double endTime_ = 0;
};

// Growth at an arbitrary time t in [0, endTime]: every spawned barb's trail in follicle space.
struct HelicalSnapshot {
  double time = 0;
  double emitterLocus[2] = {0, 0};
  glm::dvec3 emitterPoint[2];
  std::vector<uint32_t> barb;      // index into HelicalGrowth::barbs()
  std::vector<uint32_t> offset;    // barb k's points are points[offset[k] .. offset[k+1])
  std::vector<uint8_t> complete;   // per barb
  std::vector<glm::dvec3> points;  // follicle space, distal end first
};
HelicalSnapshot helicalSnapshot(const HelicalGrowth& g, double t);

// Incremental stepping for animation (Algorithm 1's Update(dt)): spawns barbs and appends trail points
// as time advances. Storage is flat: a barb gets its final block of samples when it spawns. The samples
// after any sequence of steps reaching time t equal those of helicalSnapshot(g, t).
class HelicalState {
 public:
  explicit HelicalState(const HelicalGrowth& g);  // g must outlive the state
  void reset();
  void step(double dt);  // advances min(dt, endTime - time); dt >= 0
  double time() const { return t_; }
  bool finished() const { return t_ >= g_->endTime(); }
  size_t spawnedCount() const { return barbs_.size(); }
  // Current geometry in the snapshot layout.
  HelicalSnapshot snapshot() const;

 private:
  struct Active {
    uint32_t barb, first, capacity, filled;
  };
  const HelicalGrowth* g_;
  double t_ = 0;
  uint32_t nextSpawn_[2] = {0, 0};  // position in g_->barbs() per vane
  std::vector<Active> barbs_;
  std::vector<double> loci_, stamps_;
};

// ---------------------------------------------------------------------------------------------------
// The grown feather at endTime, completed barbs only, unfurled and in the feather-local frame
// (docs/architecture.md): +x the rachis from the collar (x = 0) to the tip, +y left vane, +z dorsal
// (the outside of the collar at the anterior polar).
struct HelicalFeatherBarb {
  uint8_t vane = 0;
  uint32_t growthIndex = 0;       // index into HelicalGrowth::barbs()
  double attach = 0;              // height of the proximal end = x of the attachment on the rachis
  uint32_t first = 0, count = 0;  // points[first .. first+count), proximal (I_A) to distal
};
struct HelicalFeather {
  double length = 0;       // rachis tip height v_grow * t_end (scene units)
  double rachisWidth = 0;  // arc length of I_A
  double endTime = 0;
  std::vector<HelicalFeatherBarb> barbs;  // per vane (left first), base to tip
  std::vector<glm::dvec3> points;
};
// Unfurls with the given weights (default: the parameters' unfurlLeft/unfurlRight).
HelicalFeather helicalFeather(const HelicalGrowth& g);
HelicalFeather helicalFeather(const HelicalGrowth& g, double unfurlLeft, double unfurlRight);
// The feather as it is at growth time `time` in [0, endTime] (throws Error otherwise): the barbs that
// have fused with the rachial ridge by then, at heights v_grow (time - stamp); length v_grow time,
// endTime = time. helicalFeather(g, wL, wR) == helicalFeatherAt(g, g.endTime(), wL, wR).
HelicalFeather helicalFeatherAt(const HelicalGrowth& g, double time, double unfurlLeft, double unfurlRight);
// Unfurls one barb trail in place. pts: collar-plane points (x, y) and heights, distal end first,
// followed by the anchor at the anterior polar C(0); anchorDir the unit direction pointing distally from
// the anchor along the collar. Horizontal turning angles are scaled by (1 - w).
void unfurlTrail(std::vector<glm::dvec2>& xy, glm::dvec2 anchorDir, double w);

// ---------------------------------------------------------------------------------------------------
// Barb spacing diagnostics on the flattened (w = 1) vane, per vane.
//  - edge spacings: distances between consecutive barbs' distal ends (the vane edge), spawn order.
//  - tipSpacing: mean edge spacing from each tip barb (distal end in the distal 5% of the feather
//    length; at least the first two barbs) to the next; medianSpacing: median of all edge spacings;
//    tipRatio = tipSpacing / medianSpacing, tipMaxRatio = largest tip spacing / medianSpacing.
//    Zhang & Kanai report abnormal barb density at the tip in Time mode (the spacing there follows the
//    emitter speed, then drops to v_grow / f once the emitter is clamped); ArcLength mode keeps both
//    ratios near 1.
//  - nearEdge / nearRachis: median perpendicular distance between consecutive body barbs (spawned after
//    the emitter clamped, so neighbours are translated copies) measured 10%
//    of the barb length from its distal / proximal end (the paper observes nearEdge < nearRachis).
struct VaneSpacingStats {
  int barbs = 0;
  int tipBarbs = 0;
  double tipSpacing = 0;
  double medianSpacing = 0;
  double tipRatio = 0;
  double tipMaxRatio = 0;
  double nearEdge = 0;
  double nearRachis = 0;
  double width = 0;  // max distance of a distal end from the rachis axis (flat vane)
};
struct HelicalSpacingStats {
  VaneSpacingStats vane[2];
};
HelicalSpacingStats helicalSpacingStats(const HelicalGrowth& g);

// ---------------------------------------------------------------------------------------------------
// Conversion to an ordinary feather (generator "streit" fields): straight rachis of the grown length
// scaled to a target length (HelicalParams::length, else the rachisLength argument, else unscaled),
// barb angle pi/2 with key barbs = least-squares Bezier fits of selected unfurled barbs (chosen until
// linear interpolation between key barbs reproduces every barb within keyBarbTolerance of its chord),
// per-vane silhouette = chord length of every barb (tapering to 0 at the rachis tip), spacing fitted
// linearly to the attachment gaps, rachis width = arc length of I_A, calamus = 10% of the rachis.
struct HelicalConversion {
  FeatherParams feather;
  double scale = 1;        // output units per growth unit
  double maxFitError = 0;  // max polyline-to-Bezier distance over all barbs / grown length
  int keyBarbs[2] = {0, 0};
  int barbs[2] = {0, 0};  // converted barbs per vane (degenerate zero-chord barbs skipped)
};
HelicalConversion convertHelical(const HelicalGrowth& g, const HelicalFeather& f, double rachisLength = 0);
// Same, with the output units per growth unit given (a growing feather keeps its mature feather's
// scale, so its rachis is scale * v_grow * time). f may have zero length (time 0): a bare rachis.
HelicalConversion convertHelicalScaled(const HelicalGrowth& g, const HelicalFeather& f, double scale);
FeatherParams helicalToFeatherParams(const HelicalParams& p, const std::string& file = {});
// Moves a conversion's barbs into p: rachis length, silhouette, both vanes and spacing (barbLength 0);
// the rest of p is kept.
void adoptConvertedBarbs(FeatherParams& p, HelicalConversion&& c);
// Derives the barb fields of p from helical parameters: rachis length stays p.rachisLength unless
// hp.length is set; barbs (silhouette, key barbs, angles, spacing) are replaced; calamus, rachis width
// and curvature, splits, material, seed and afterfeather are kept. The one-argument form reads hp from
// p.generatorParams (helicalToJson form). Throws Error naming p.sourceFile for invalid parameters.
void applyHelical(FeatherParams& p);
void applyHelical(FeatherParams& p, const HelicalParams& hp);

// Least-squares Bezier fit with fixed end points and chord-length parameters refined by projection.
// Returns `cvCount` (2..16) control vertices. Polylines of more than 64 points are first thinned to 64
// evenly spaced ones (end points kept); maxError (optional) receives the max distance from those
// points to the curve.
std::vector<glm::dvec3> fitBezier(const glm::dvec3* pts, size_t n, int cvCount, double* maxError = nullptr);

// ---------------------------------------------------------------------------------------------------
// A helical feather in a growing coat (docs/growth.md, "Helical feathers"): the schedule's stages are
// mapped to the helical model. Collar growth plays over the shaft and barb windows, unfurling over the
// opening window, and the open stage turns the unfurled barbs into the feather's own key barbs.
struct HelicalGrowthStage {
  double collar = 1;      // growth time / endTime = (shaft_length + barb_length) / 2
  double unfurlLeft = 0;  // w per vane = the parameters' unfurl * opening
  double unfurlRight = 0;
  double open = 1;       // key_barbs: the grown helical form (0) -> the feather's own key barbs (1)
  double curvature = 1;  // rachis_curvature: the rachis (and split openings) curve
};
HelicalGrowthStage helicalGrowthStage(const GrowthState& st, const HelicalParams& hp);
// The helical generator's grow hook (featherAtState calls it for growing states): the feather grown by
// the helical model at the stage's time and unfurl weights, converted at the mature feather's scale
// (rachis = def.rachisLength * collar), with def's calamus, rachis width (times shaft_width), material
// and afterfeather (grown by the schedule). Returns the Streit form (generator "streit"). Throws Error
// naming def.sourceFile for unusable helical parameters.
FeatherParams growHelical(const FeatherParams& def, const GrowthState& st, const GrowthSchedule& s);

// The "helical" feather generator hooks (FeatherParams::generator == "helical", settings in a
// "helical" object of the feather file): read parses and validates the object, stores it in
// generatorParams and derives the Streit fields with applyHelical(), so generateBarbs, meshing and
// packing use the ordinary path. Registered in registerBuiltinFeatherGenerators().
FeatherGenerator helicalFeatherGenerator();

}  // namespace pteryla::feather
