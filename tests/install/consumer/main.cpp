// Feathers a mesh held in memory through the installed host API only (include "pteryla/pteryla.hpp",
// link libpteryla), then checks what a host relies on. Exit 0 when every check passes.
//   consumer [PREFIX]   PREFIX: the install prefix the data directory must be found under
#include <pteryla/pteryla.hpp>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "icosphere.hpp"

namespace {

int failures = 0;

void check(bool ok, const std::string& what) {
  std::printf("%s %s\n", ok ? "ok  " : "FAIL", what.c_str());
  if (!ok) ++failures;
}

bool finite(const pteryla::View<float>& v) {
  for (float x : v)
    if (!std::isfinite(x)) return false;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    std::printf("pteryla %s, data %s\n", pteryla::version(), pteryla::dataDirectory().c_str());
    if (argc > 1) {
      const std::string prefix = argv[1];
      check(pteryla::dataDirectory().rfind(prefix, 0) == 0, "the data directory is found beside the installed library");
    }

    const pteryla_test::Icosphere ico = pteryla_test::icosphere(3);
    pteryla::SkinArrays skin;
    skin.positions = ico.positions;
    skin.triangles = ico.triangles;
    pteryla::CoatSetup setup;
    pteryla::TractSetup body;
    body.name = "body";
    body.count = 80;
    setup.tracts.push_back(body);
    setup.axis = {{{0, 1.2, 0}}, {{0, -1.2, 0}}};

    pteryla::Session session(skin, setup);
    session.setLod(0.3);
    check(session.evaluate(), "evaluate() completes");
    const pteryla::Frame& rest = session.frame();
    check(rest.featherCount == 80, "80 feathers, got " + std::to_string(rest.featherCount));
    check(rest.indices.size > 0 && rest.indices.size % 3 == 0,
          std::to_string(rest.indices.size / 3) + " coat triangles");
    check(finite(rest.positions) && finite(rest.vertexNormals), "coat vertices and normals are finite");
    const std::vector<float> before(rest.positions.begin(), rest.positions.end());
    const std::vector<uint64_t> keys(rest.follicleKeys.begin(), rest.follicleKeys.end());

    // The host moves its mesh: the coat follows, on the same follicles.
    std::vector<double> posed = skin.positions;
    for (size_t v = 0; v < posed.size(); v += 3) posed[v] += 0.5;
    session.setPose(posed);
    check(session.evaluate(), "evaluate() after setPose completes");
    const pteryla::Frame& moved = session.frame();
    bool sameKeys = moved.featherCount == keys.size();
    for (size_t i = 0; sameKeys && i < keys.size(); ++i) sameKeys = moved.follicleKeys[i] == keys[i];
    check(sameKeys, "the pose keeps every follicle");
    double shift = 0;
    for (size_t k = 0; k + 2 < moved.positions.size && k < before.size(); k += 3)
      shift += moved.positions[k] - before[k];
    shift /= double(before.size() / 3);
    check(moved.positions.size == before.size() && std::abs(shift - 0.5) < 1e-3,
          "the coat moved with the skin (mean x shift " + std::to_string(shift) + ")");
    check(finite(moved.positions), "posed coat vertices are finite");

    // Errors cross the library boundary as pteryla::Error with their element.
    std::string element;
    try {
      session.setPose(std::vector<double>(5, 0.0));
    } catch (const pteryla::Error& e) {
      element = e.element();
    }
    check(element == "positions", "a wrong pose is a pteryla::Error naming 'positions' (got '" + element + "')");

    // A bundled scene from the installed data directory.
    pteryla::Session scene = pteryla::Session::fromSceneFile(pteryla::dataDirectory() + "/scenes/sphere_250.json");
    check(scene.evaluate() && scene.frame().featherCount == 426, "the installed sphere_250 scene evaluates");
  } catch (const std::exception& e) {
    std::printf("FAIL exception: %s\n", e.what());
    return 1;
  }
  std::printf("%s\n", failures ? "FAILED" : "PASSED");
  return failures ? 1 : 0;
}
