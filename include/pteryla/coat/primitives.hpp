#pragma once
// Generated skin meshes for tests, benchmarks and demos. All go through makeSkinMesh (validated, with
// adjacency and normals), so they behave exactly like loaded meshes.
#include <glm/vec3.hpp>

#include "pteryla/coat/skin.hpp"

namespace pteryla::coat {

// Icosahedron subdivided `subdivisions` times (20 * 4^s faces), vertices on the sphere, outward normals.
SkinMesh makeIcosphere(int subdivisions, double radius = 1.0, const glm::dvec3& center = glm::dvec3(0));

// Flat rectangle [0,sizeX] x [0,sizeY] in the z = 0 plane (normal +z), nx x ny quads split into
// triangles with alternating diagonals. Has a boundary.
SkinMesh makeGridPatch(int nx, int ny, double sizeX = 1.0, double sizeY = 1.0);

// Torus around the z axis (genus 1, closed): major radius R, tube radius r, nu x nv quads.
SkinMesh makeTorus(int nu, int nv, double majorRadius = 1.0, double minorRadius = 0.35);

// Open cylinder around the z axis from z = 0 to height (two boundary loops), nu x nv quads.
SkinMesh makeCylinder(int nu, int nv, double radius = 1.0, double height = 2.0);

}  // namespace pteryla::coat
