#pragma once
// Barb generation (Streit 2003, 5.2.2 and 5.2.5): from FeatherParams to the shaft polyline and every
// barb as a Bezier curve in feather-local coordinates. Output is flat: one array of barb records and one
// array of control vertices, so a coat of thousands of feathers generates without per-barb allocation.
#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

#include "pteryla/feather/params.hpp"

namespace pteryla::feather {

// Orthonormal frame on the shaft at rachis position rp (feather-local coordinates).
struct RachisFrame {
  glm::dvec3 point;    // on the rachis centre line
  glm::dvec3 tangent;  // toward the tip
  glm::dvec3 left;     // in the vane plane, toward the left vane (+y for a straight shaft)
  glm::dvec3 dorsal;   // vane normal, dorsal side (+z for a straight shaft)
  double width = 0;    // rachis width (diameter), scene units
};
// Rachis is a circular arc of length rachisLength from (calamusLength, 0, 0), tangent +x, bending by the
// two curvature angles; rp is arc length / rachisLength.
RachisFrame rachisFrame(const FeatherParams& p, double rp);
// The same arc as a cubic Bezier (4 control vertices, standard arc approximation).
std::vector<glm::dvec3> rachisBezier(const FeatherParams& p);

// Barb attachment positions along the rachis, as rp values ascending from 0. Spacing is linear in
// arc length s: sp(s) = spacingBase + (spacingTip - spacingBase) s / rachisLength, and positions solve
// ds/dk = sp(s) exactly: s_k = spacingBase (e^{ck} - 1) / c with c = (spacingTip - spacingBase) / L
// (s_k = k spacingBase when c = 0). Count = floor(k(L)) + 1 (plus 1e-9 slack for exact fits).
void barbPositions(const FeatherParams& p, std::vector<double>& rps);
size_t barbCount(const FeatherParams& p);

struct BarbCurve {
  glm::vec3 root{0.0f};   // attachment point on the rachis, feather-local
  float rp = 0;           // [0,1]
  float angle = 0;        // radians between rachis tangent and barb in the vane plane (after splits)
  float length = 0;       // barb length scale applied (scene units)
  uint32_t cvOffset = 0;  // first control vertex in FeatherCurves::cvs
  uint16_t cvCount = 0;
  uint8_t vane = 0;          // 0 left (+y), 1 right (-y)
  uint8_t part = 0;          // 0 main feather, 1 afterfeather
  bool isKey = false;        // nearest barb to a key barb given in the parameters (LOD keeps these longest)
  bool isSplitEdge = false;  // borders a vane split
  bool splitAfter = false;   // no vane surface between this barb and the next one of the same vane/part
};

// One shaft (calamus + rachis) as a polyline with widths.
struct ShaftCurve {
  std::vector<glm::vec3> points;     // from the follicle (x = 0) to the rachis tip
  std::vector<float> widths;         // diameter at each point (0 at the tip)
  std::vector<float> rp;             // rachis position per point; < 0 on the calamus (-1 at the follicle)
  glm::vec3 dorsal[2];               // dorsal direction at the umbilicus and at the tip
  std::vector<glm::vec3> rachisCvs;  // rachis as a cubic Bezier, feather-local
  int calamusPoints = 0;             // points[0 .. calamusPoints) lie on the calamus
};

struct FeatherCurves {
  // parts[0]: the main feather, parts[1]: the afterfeather when present (generated in the main
  // feather's frame, translated to the superior umbilicus (calamusLength, 0, -rachisWidth / 2)). Barbs of part i are
  // barbs[barbBegin[i] .. barbEnd[i]); left-vane barbs come first, each vane ordered base to tip.
  std::vector<ShaftCurve> shafts;
  std::vector<uint32_t> barbBegin, barbEnd;
  std::vector<BarbCurve> barbs;
  std::vector<glm::vec3> cvs;  // all barb control vertices, feather-local
  size_t partCount() const { return shafts.size(); }
  void clear();  // keeps capacity
};

struct GenerateOptions {
  int shaftSegments = 16;    // rachis polyline segments (the calamus gets 2)
  bool afterfeather = true;  // generate the afterfeather's curves when present
};

// Generates every barb of the feather (and its afterfeather). Throws Error for invalid parameters.
FeatherCurves generateBarbs(const FeatherParams& p, const GenerateOptions& opt = {});
// Same, reusing `out`'s storage (no allocation once capacities are reached).
void generateBarbs(const FeatherParams& p, FeatherCurves& out, const GenerateOptions& opt = {});

// Sampled barb polyline (segments+1 points) for barb `b` of `c`.
void barbPolyline(const FeatherCurves& c, const BarbCurve& b, int segments, std::vector<glm::vec3>& out);

// Wear splits of one vane (5.2.5), reproducible from p.seed. In generateBarbs the two barbs around each
// split get isSplitEdge (the lower one splitAfter) and open away from each other by opening/2 each;
// up to SplitParams::reach barbs per side follow their edge barb with a linearly falling share.
struct VaneSplit {
  double rp;       // split location
  double opening;  // radians
};
std::vector<VaneSplit> vaneSplits(const FeatherParams& p, int vane);

}  // namespace pteryla::feather
