#pragma once
// Poulin-Fournier anisotropic reflection of parallel cylinders (barbules), tabulated for the
// renderer as the thesis does (Streit 2003, 7.1.3). Formulas and conventions follow
// shared/reference/poulin-fournier.md, which was checked against a ray caster:
//  - frame at a barbule: T the cylinder axis, N the macro normal, B = T x N;
//  - phi is the signed angle of a direction projected into the (B, N) plane, measured from N,
//    positive toward +B; the table is indexed by alpha = angle(B, projected direction) in [0, pi],
//    so phi = pi/2 - alpha;
//  - D is the diffuse factor, normalised by the visible projected width d cos(phi_V), such that the
//    reflected radiance is albedo * E * |L'| * D (|L'| is the length of the projected unit light);
//  - S is the same with a Gaussian lobe of width sigma around the in-plane mirror normal.
// Pure CPU code (no GL).
#include <cstddef>
#include <vector>

namespace pteryla::render {

struct BarbuleParams {
  double d = 1.0;      // spacing of unit-radius cylinders; > 0. d -> 0 is Lambertian, d >= 2 adds a floor
  double h = 0.0;      // floor height in [0, 1); h -> 1 is Lambertian
  double sigma = 0.2;  // specular lobe width, radians; > 0
};

// Throws pteryla::Error naming the bad field ("d", "h", "sigma").
void validate(const BarbuleParams& p);

// Exposed (lit or visible) part of one period for a direction at signed angle phi (radians):
// arc [arcLo, arcHi] (angles from N) and floor interval [floorLo, floorHi] measured from the
// cylinder's foot toward +B. Formula (1) of the reference.
struct ExposedSet {
  double arcLo = 0, arcHi = 0;
  double floorLo = 0, floorHi = 0;
};
ExposedSet exposedSet(double phi, double d, double h);

// Closed-form diffuse term D(phi_L, phi_V) (reference formula (2)); angles in radians, |phi| < pi/2.
double barbuleDiffuse(double phiL, double phiV, double d, double h);
// Gaussian specular term S(phi_L, phi_V) (reference formula (3)), 64-point Gauss-Legendre on each
// side of the half angle.
double barbuleSpecular(double phiL, double phiV, double d, double h, double sigma);

// N x N table over (alpha_L, alpha_V) in [0, pi]^2 at cell centres alpha_i = (i + 1/2) pi / N, two
// channels (D, S) interleaved: value(iL, iV, c) = data[(iV * N + iL) * 2 + c]. Uploaded as an RG
// float texture with s = alpha_L / pi and t = alpha_V / pi, bilinear, clamp-to-edge.
struct BrdfTable {
  int size = 0;
  std::vector<float> data;

  float at(int iL, int iV, int channel) const { return data[(static_cast<size_t>(iV) * size + iL) * 2 + channel]; }
  // Bilinear lookup with clamp-to-edge, exactly as the GPU samples the texture.
  float sample(double alphaL, double alphaV, int channel) const;
};

// Builds the table (recommended size 128). Every entry is finite and >= 0.
BrdfTable buildBrdfTable(const BarbuleParams& params, int size = 128);

}  // namespace pteryla::render
