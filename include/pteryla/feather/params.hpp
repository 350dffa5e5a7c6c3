#pragma once
// Feather parameters after Streit 2003, Table 5.1 and section 5.2: a feather is a calamus, a rachis
// (a Bezier arc with lateral and ventral-dorsal curvature), two vanes described by barb angles and a few
// key barbs (Bezier curves) from which every other barb is interpolated, barb spacing and length
// (constant or a silhouette profile), wear splits, and an optional afterfeather that has the same
// parameter set. Plain value types: copy freely; the afterfeather is shared immutable data.
//
// Frames (docs/architecture.md): feather-local +x along the shaft from the follicle to the tip, +y the
// left vane, +z dorsal. A key barb lives in a barb-local unit frame: +x along the barb away from the
// rachis, +y in the vane plane toward the feather tip, +z dorsal; cv[0] is the attachment point (the
// curve is translated so that cv[0] is the origin when used). The chord |cv[n] - cv[0]| is clamped to
// [0,1]; barbs are then scaled by the barb length, so a key barb with chord 1 reaches exactly the barb
// length and a shorter chord gives a shorter barb (vane discontinuities, 5.2.2).
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace pteryla::feather {

struct GrowthSchedule;  // growth.hpp

inline constexpr double kPi = 3.14159265358979323846;

struct KeyBarb {
  double rp = 0;                // attachment position along the rachis, [0,1] (0 base, 1 tip)
  std::vector<glm::dvec3> cvs;  // >= 2 control vertices, barb-local unit frame
  bool operator==(const KeyBarb& o) const { return rp == o.rp && cvs == o.cvs; }
};

struct VaneParams {
  double baseAngle = 0.9;         // radians between rachis (toward the tip) and barb at rp = 0
  double tipAngle = 0.6;          // radians at rp = 1; linear in between
  std::vector<KeyBarb> keyBarbs;  // sorted by rp (loading sorts stably); empty -> defaults (down)
  bool operator==(const VaneParams& o) const {
    return baseAngle == o.baseAngle && tipAngle == o.tipAngle && keyBarbs == o.keyBarbs;
  }
};

// Barb length as a piecewise-linear function of rp: points (rp, length in scene units), rp ascending
// in [0,1]; clamped beyond the ends. Empty = use FeatherParams::barbLength.
struct LengthProfile {
  std::vector<glm::dvec2> points;
  bool empty() const { return points.empty(); }
  double at(double rp) const;
  bool operator==(const LengthProfile& o) const { return points == o.points; }
};

// Silhouette data (5.2.3): per-vane barb length profiles, e.g. from silhouetteFromOutline() or an image.
struct Silhouette {
  LengthProfile left, right;
  bool empty() const { return left.empty() && right.empty(); }
  bool operator==(const Silhouette& o) const { return left == o.left && right == o.right; }
};

// Wear splits in the vane (5.2.5). Locations are drawn from FeatherParams::seed, per vane.
struct SplitParams {
  int count = 0;        // splits per vane
  double rpMin = 0.25;  // split locations are uniform in [rpMin, rpMax]
  double rpMax = 0.95;
  double openingAngle = 0.12;  // radians; each split opens by a random angle in [0.5, 1] * this
  int reach = 3;               // barbs on each side of a split that follow the edge barb's angle
  bool operator==(const SplitParams& o) const {
    return count == o.count && rpMin == o.rpMin && rpMax == o.rpMax && openingAngle == o.openingAngle &&
           reach == o.reach;
  }
};

// Optional look information carried for the renderer; the feather model does not interpret it.
// Texture paths are stored as written (resolve against FeatherParams::sourceFile).
struct FeatherMaterial {
  std::string texture;                  // colour texture
  std::string alphaTexture;             // alpha texture
  std::string pattern;                  // procedural pattern name
  std::optional<glm::dvec3> baseColor;  // linear RGB in [0,1]
  // Which texture mapping of Streit 2003, 7.1.1 addresses the colour texture: "global" (the whole vane:
  // u across, v base to tip; the default), "barb" (glued to each barb: u along it, v across) or
  // "growth" (the pin-feather cone: u around it, v along the shaft). docs/feather-format.md.
  std::string uv = "global";
  // "brdf": this feather's Poulin-Fournier barbule spacing d and floor height h (Streit 2003, 7.1.3);
  // unset = the scene's render.brdf. docs/feather-format.md.
  std::optional<double> brdfD, brdfH;
  bool empty() const {
    return texture.empty() && alphaTexture.empty() && pattern.empty() && !baseColor && uv == "global" && !brdfD &&
           !brdfH;
  }
  bool operator==(const FeatherMaterial& o) const {
    return texture == o.texture && alphaTexture == o.alphaTexture && pattern == o.pattern && baseColor == o.baseColor &&
           uv == o.uv && brdfD == o.brdfD && brdfH == o.brdfH;
  }
};

struct FeatherParams {
  std::string name;
  // Which generator builds the barbs: "streit" (this module, 5.2.2) or one added through
  // registerFeatherGenerator() (generator.hpp). Generator-specific settings live in generatorParams.
  std::string generator = "streit";
  nlohmann::json generatorParams;  // null for "streit"

  // Calamus (Table 5.1: c_l, c_wr). Width at the follicle = calamusWidthRatio * rachisWidth, so the
  // calamus meets the rachis without a discontinuity.
  double calamusLength = 0.05;  // scene units
  double calamusWidthRatio = 0.8;
  // Rachis (r_l, r_w, r_lc, r_vdc). Width tapers linearly from rachisWidth at the umbilicus to a point.
  double rachisLength = 1.0;  // scene units (arc length)
  double rachisWidth = 0.02;  // scene units
  // Curvatures are the total turning angle of the rachis tangent from base to tip, radians (the
  // rachis is a circular arc, so the shape is scale independent). Lateral > 0 bends toward +y (the
  // left vane); ventral-dorsal > 0 bends the tip toward -z (toward the body).
  double rachisLateralCurvature = 0;
  double rachisVentralDorsalCurvature = 0;

  double barbLength = 0.3;  // scene units, when silhouette is empty
  Silhouette silhouette;    // optional barb length profiles (override barbLength per vane)
  VaneParams left, right;
  double spacingBase = 0.01;  // distance along the rachis between barbs at rp = 0, scene units
  double spacingTip = 0.01;   // ... at rp = 1; linear in between; same on both vanes
  SplitParams splits;
  uint64_t seed = 1;  // default plumulaceous barb and split locations

  FeatherMaterial material;
  // Afterfeather: secondary feather at the superior umbilicus (top of the calamus), same parameters.
  std::shared_ptr<const FeatherParams> afterfeather;
  // Growth and wear schedule (growth.hpp, docs/growth.md) from the feather file's "growth" object, or
  // the one a scene or tract gives its feathers; null = defaultGrowthSchedule(). Compared by value.
  std::shared_ptr<const GrowthSchedule> growth;

  std::string sourceFile;  // set by loadFeather(); not serialized, ignored by ==

  const VaneParams& vane(int v) const { return v == 0 ? left : right; }
  VaneParams& vane(int v) { return v == 0 ? left : right; }
  // Barb length at rp on vane v (0 left, 1 right).
  double barbLengthAt(int v, double rp) const;
  double totalLength() const { return calamusLength + rachisLength; }

  bool operator==(const FeatherParams& o) const;
  // Everything but the vanes' key barbs (their angles included) is equal.
  bool equalExceptKeyBarbs(const FeatherParams& o) const;
  bool operator!=(const FeatherParams& o) const { return !(*this == o); }
};

// Default key barbs (5.2.2). B_df1: plumulaceous, four control vertices jittered along a line with
// displacement growing toward the tip, drawn from `seed`; chord <= 1. B_df2: straight barb with a slight
// front-to-back (ventral) curvature, chord 1.
std::vector<glm::dvec3> defaultPlumulaceousBarb(uint64_t seed);
std::vector<glm::dvec3> defaultPennaceousBarb();

// The key barbs actually used for a vane, sorted by rp, with the defaults made explicit: no key barbs
// -> {B_df1 at 0, B_df1 at 1} (down); otherwise B_df1 at rp 0 unless a key barb is there, B_df2 at rp 1
// unless a key barb is there. Control vertices are translated so cv[0] = 0, chord-clamped to <= 1 and
// degree-elevated to a common count (so consumers can lerp component-wise).
std::vector<KeyBarb> effectiveKeyBarbs(const FeatherParams& p, int vane);

// Barb shape (barb-local, unit scale) at rp from a list as returned by effectiveKeyBarbs (eq. 5.1):
// linear interpolation of the key barbs immediately below and above. When several key barbs share rp
// (a discontinuity), the upper one wins; pass `hint` = index of a key barb to select that one exactly
// when rp equals its position. Writes `out` (resized to the common count).
void barbShapeAt(const std::vector<KeyBarb>& keys, double rp, std::vector<glm::dvec3>& out, int hint = -1);

// Throws pteryla::Error (element = parameter name) for values the generator cannot use: non-finite or
// negative lengths, spacing <= 0, rp outside [0,1], fewer than 2 control vertices, angles outside
// (0, pi), .... `file` goes into the error.
void validateFeather(const FeatherParams& p, const std::string& file = {});

}  // namespace pteryla::feather
