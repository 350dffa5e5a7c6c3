// pteryla_packdiag: where a scene's packed coat intersects itself and the skin (issue #8 diagnostics).
// Evaluates a scene like `pteryla check` and breaks the checker's counts down per tract: feathers,
// elevations, pack statistics, intersecting triangle pairs at full geometry (and the unpacked proxy's),
// the tract pairs they fall between, skin penetrations and coverage.
//
//   pteryla_packdiag SCENE.json [--set /json/pointer=JSON ...] [--no-full] [--lod F] [--top N] [--tract NAME]
//                    [--cover] [--face-cover FILE] [--blame N] [--flat DEG] [--scale K]
//                    [--follicles FILE]
//
// --blame N: which feathers under feather N raise it. For each feather before N in layer order within
// reach, N is packed again over the pack without that feather (packOver); the ones whose absence lowers N
// the most are listed.
// --face-cover FILE writes one line per skin face, "samples uncovered", from the full check's coverage
// samples (for a coverage map of the skin, e.g. tools/packdiag/cover_map.py).
//
// --flat DEG holds every feather at DEG degrees (a styling selection appended to the scene's, so it wins
// over their elevations; directions and other keys stay): with collisions ignored, the coverage that the
// follicles, directions and feather sizes allow at that elevation. --scale K multiplies every tract's
// feather length (feather_scale, or feather_spacings where the scale is "auto"). Together they measure
// how far the coat's design, not the packer, limits coverage (docs/packing.md).
//
// --set edits the scene JSON before loading (e.g. --set /packing/shaft_band=0.5), so parameter
// experiments need no scratch scene files. --no-full skips the slow full-geometry checks (the proxy
// mesh of the packed coat is measured instead).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "pteryla/coat/check.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/style.hpp"
#include "pteryla/coat/tracts.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"

using namespace pteryla;

namespace {

double pct(const std::vector<double>& v, double q) {
  if (v.empty()) return NAN;
  std::vector<double> s = v;
  std::sort(s.begin(), s.end());
  return s[std::min(s.size() - 1, static_cast<size_t>(q * (s.size() - 1) + 0.5))];
}

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const char* usage =
        "usage: %s SCENE.json [--set /pointer=JSON ...] [--no-full] [--lod F] [--top N] [--tract NAME] [--cover] "
        "[--face-cover FILE] [--blame N] [--flat DEG] [--scale K] [--follicles FILE]\n";
    if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0) {
      std::fprintf(argc < 2 ? stderr : stdout, usage, argv[0]);
      return argc < 2 ? 2 : 0;
    }
    const std::string path = argv[1];
    bool full = true, cover = false;
    std::string listTract;      // --tract NAME: one line per feather of that tract (follicle, frame, elevations)
    std::string faceCoverPath;  // --face-cover FILE
    std::string folliclesPath;  // --follicles FILE: "tract x y z length" per feather, then exit
    long blame = -1;            // --blame N
    double lod = 1.0;
    double flatDeg = NAN;    // --flat DEG
    double lengthScale = 1;  // --scale K
    int top = 15;
    std::vector<std::pair<std::string, std::string>> sets;
    for (int a = 2; a < argc; ++a) {
      const std::string s = argv[a];
      if (s == "--no-full")
        full = false;
      else if (s == "--cover")
        cover = true;
      else if (s == "--lod" && a + 1 < argc)
        lod = std::stod(argv[++a]);
      else if (s == "--top" && a + 1 < argc)
        top = std::stoi(argv[++a]);
      else if (s == "--tract" && a + 1 < argc)
        listTract = argv[++a];
      else if (s == "--face-cover" && a + 1 < argc)
        faceCoverPath = argv[++a];
      else if (s == "--follicles" && a + 1 < argc)
        folliclesPath = argv[++a];
      else if (s == "--blame" && a + 1 < argc) {
        const std::string v = argv[++a];
        char* end = nullptr;
        blame = std::strtol(v.c_str(), &end, 10);
        if (v.empty() || *end != '\0' || blame < 0)
          throw Error("--blame expects a feather index (a non-negative integer)", {}, v);
      } else if ((s == "--flat" || s == "--scale") && a + 1 < argc) {
        const std::string v = argv[++a];
        char* end = nullptr;
        const double x = std::strtod(v.c_str(), &end);
        if (s == "--flat" && (v.empty() || *end != '\0' || !(x >= 0 && x <= 90)))
          throw Error("--flat expects an elevation in degrees in [0, 90]", {}, v);
        if (s == "--scale" && (v.empty() || *end != '\0' || !(x > 0 && std::isfinite(x))))
          throw Error("--scale expects a positive length factor", {}, v);
        (s == "--flat" ? flatDeg : lengthScale) = x;
      } else if (s == "--set" && a + 1 < argc) {
        const std::string kv = argv[++a];
        const size_t eq = kv.find('=');
        if (eq == std::string::npos) throw Error("--set needs /pointer=JSON", {}, kv);
        sets.emplace_back(kv.substr(0, eq), kv.substr(eq + 1));
      } else {
        throw Error("unknown argument", {}, s);
      }
    }
    std::ifstream in(path);
    if (!in) throw Error("cannot open", path, {});
    nlohmann::json j = nlohmann::json::parse(in);
    for (const auto& [ptr, val] : sets) j[nlohmann::json::json_pointer(ptr)] = nlohmann::json::parse(val);
    if (!std::isnan(flatDeg))
      j["packing"]["styling"].push_back(
          {{"select", "sphere"}, {"center", {0, 0, 0}}, {"radius", 1e9}, {"elevation_deg", flatDeg}});
    if (lengthScale != 1 && j.contains("tracts"))
      for (auto& t : j["tracts"]) {  // scene-format.md: feather_scale defaults to 1, feather_spacings to 3.5
        const bool automatic = t.contains("feather_scale") && t["feather_scale"] == "auto";
        if (automatic)
          t["feather_spacings"] = t.value("feather_spacings", 3.5) * lengthScale;
        else
          t["feather_scale"] = t.value("feather_scale", 1.0) * lengthScale;
      }
    pipeline::Pipeline p(pipeline::sceneFromJson(j, path));

    auto t0 = std::chrono::steady_clock::now();
    const coat::CoatFeathers& coat = p.feathers();
    const std::vector<double> elev = p.elevations();
    const auto& tracts = p.tracts();
    const coat::SkinMesh& skin = p.posedSkin();
    const size_t n = coat.size();
    std::printf("evaluated %zu feathers in %.1f s\n", n, secondsSince(t0));
    if (!folliclesPath.empty()) {  // for tools/scenes/make_bird_scene.py (BIRD_FOLLICLES, BIRD_UNSCALED)
      std::ofstream out(folliclesPath);
      out.precision(9);
      for (size_t i = 0; i < n; ++i)
        out << tracts[coat.tract[i]].name << ' ' << coat.frames[i].origin.x << ' ' << coat.frames[i].origin.y << ' '
            << coat.frames[i].origin.z << ' ' << coat.params[i].totalLength() << '\n';
      if (!out) throw Error("cannot write", folliclesPath, {});
      return 0;
    }

    // Re-pack with the scene's options for the statistics (deterministic: must equal the pipeline's).
    coat::PackingSettings packing;
    if (j.contains("packing")) {
      JsonReader r(j["packing"], path, "packing");
      packing = coat::parsePackingSettings(r);
    }
    coat::PackConstraints styled;
    styled.fixedElevation = coat::resolveStyling(coat, packing.styling);
    styled.minElevation = coat::resolveMinElevation(coat, packing.styling);
    styled.shaftBand = coat::resolveShaftBand(coat, packing.styling);
    t0 = std::chrono::steady_clock::now();
    const coat::PackResult pr = coat::pack(skin, coat, packing.options, styled);
    size_t same = 0;
    for (size_t i = 0; i < n; ++i) same += pr.elevation[i] == elev[i] ? 1 : 0;
    const auto& st = pr.stats;
    std::printf(
        "pack %.3f s (pipeline's elevations reproduced for %zu/%zu): free %zu clamped %zu conflicts %zu "
        "unopened %zu fixed %zu barbs elevated %zu lifted %zu unresolved %zu\n",
        secondsSince(t0), same, n, st.free, st.shaftClamped, st.conflicts, st.unopened, st.fixed, st.barbsElevated,
        st.barbsLifted, st.barbsUnresolved);
    if (!listTract.empty()) {
      if (std::none_of(tracts.begin(), tracts.end(), [&](const auto& t) { return t.name == listTract; }))
        throw Error("no tract of that name in the scene", path, "--tract " + listTract);
      std::vector<uint32_t> layerPos(n, 0);
      for (size_t k = 0; k < coat.layerOrder.size(); ++k) layerPos[coat.layerOrder[k]] = static_cast<uint32_t>(k);
      for (size_t i = 0; i < n; ++i) {
        if (tracts[coat.tract[i]].name != listTract) continue;
        const auto& f = coat.frames[i];
        const double fixed = i < styled.fixedElevation.size() ? styled.fixedElevation[i] : NAN;
        std::printf(
            "  feather %zu layer %u at (%.4f %.4f %.4f) T (%.3f %.3f %.3f) N (%.3f %.3f %.3f) elevation %.2f deg "
            "fixed %.2f len %.3f\n",
            i, layerPos[i], f.origin.x, f.origin.y, f.origin.z, f.tangent.x, f.tangent.y, f.tangent.z, f.normal.x,
            f.normal.y, f.normal.z, elev[i] * 57.29578, fixed * 57.29578, coat.params[i].rachisLength);
      }
    }

    if (blame >= 0) {
      if (static_cast<size_t>(blame) >= n || !coat.present[blame])
        throw Error("--blame: no such present feather", path, std::to_string(blame));
      const uint32_t b = static_cast<uint32_t>(blame);
      std::vector<uint32_t> pos(n, UINT32_MAX);
      for (size_t k = 0; k < coat.layerOrder.size(); ++k) pos[coat.layerOrder[k]] = static_cast<uint32_t>(k);
      std::vector<std::pair<double, uint32_t>> drops;
      coat::CoatFeathers without = coat;
      for (uint32_t k = 0; k < n; ++k) {
        if (!coat.present[k] || pos[k] >= pos[b]) continue;
        const double reach = coat.params[k].totalLength() + coat.params[b].totalLength();
        if (glm::length(coat.frames[k].origin - coat.frames[b].origin) > reach) continue;
        without.present[k] = 0;
        const coat::PackResult r = coat::packOver(skin, without, pr, {b}, packing.options, styled);
        without.present[k] = 1;
        drops.push_back({pr.elevation[b] - r.elevation[b], k});
      }
      std::sort(drops.rbegin(), drops.rend());
      std::printf(
          "feather %u (%s) elevation %.2f deg; %zu feathers under it within reach; without each, it would lie at:\n", b,
          tracts[coat.tract[b]].name.c_str(), pr.elevation[b] * 180 / M_PI, drops.size());
      for (int k = 0; k < top && k < static_cast<int>(drops.size()); ++k) {
        const uint32_t q = drops[k].second;
        std::printf("  without %5u (%s, e %.1f, len %.3f, dist %.3f): %.2f deg\n", q,
                    tracts[coat.tract[q]].name.c_str(), pr.elevation[q] * 180 / M_PI, coat.params[q].totalLength(),
                    glm::length(coat.frames[q].origin - coat.frames[b].origin),
                    (pr.elevation[b] - drops[k].first) * 180 / M_PI);
      }
    }

    // Checks.
    coat::CheckOptions co;
    co.seed = p.scene().seed;
    co.attribute = true;
    coat::setFeatherBases(co, coat, packing.options.baseAllowance);
    std::vector<uint32_t> allFaces;
    for (const auto& t : tracts) allFaces.insert(allFaces.end(), t.faces.begin(), t.faces.end());
    std::sort(allFaces.begin(), allFaces.end());
    allFaces.erase(std::unique(allFaces.begin(), allFaces.end()), allFaces.end());

    const TriMesh packedProxy = coat::proxyCoatMesh(coat, pr.elevation, coat::allPackedParams(coat, pr));
    t0 = std::chrono::steady_clock::now();
    TriMesh fullMesh;
    if (full) {
      p.setLod(lod);
      fullMesh = p.coatMesh().mesh;
    }
    const TriMesh& packedMesh = full ? fullMesh : packedProxy;
    const coat::CheckResult cr = coat::check(skin, allFaces, packedMesh, co);
    std::printf("%s check %.1f s: %zu triangles, intersecting_pairs %zu, skin_penetrations %zu, coverage %.4f\n",
                full ? "full" : "proxy", secondsSince(t0), cr.coatTriangles, cr.intersectingPairs, cr.skinPenetrations,
                cr.coverage);
    if (!faceCoverPath.empty()) {
      std::ofstream fc(faceCoverPath);
      if (!fc) throw Error("cannot write", faceCoverPath, {});
      for (size_t f = 0; f < skin.faceAreas.size(); ++f)
        fc << (f < cr.faceSamples.size() ? cr.faceSamples[f] : 0) << ' '
           << (f < cr.faceUncovered.size() ? cr.faceUncovered[f] : 0) << '\n';
    }

    std::vector<double> flatE;
    for (size_t i = 0; i < n; ++i)
      if (coat.present[i]) flatE.push_back(elev[i]);
    const double median = pct(flatE, 0.5);
    const std::vector<double> flat(n, median);
    t0 = std::chrono::steady_clock::now();
    const TriMesh unpacked = coat::proxyCoatMesh(coat, flat, coat.params);
    const auto up = coat::intersectingFeatherPairs(unpacked);
    size_t upTotal = 0;
    for (const auto& q : up) upTotal += q.pairs;
    const auto pp = coat::intersectingFeatherPairs(packedProxy);
    size_t ppTotal = 0;
    for (const auto& q : pp) ppTotal += q.pairs;
    std::printf("unpacked proxy (median elevation %.1f deg) %zu pairs, packed proxy %zu pairs (%.1f s)\n",
                median * 180 / M_PI, upTotal, ppTotal, secondsSince(t0));

    // Per tract.
    const size_t nt = tracts.size();
    std::vector<size_t> tf(nt, 0), tPairs(nt, 0), tUp(nt, 0), tPp(nt, 0), tPen(nt, 0), tPenF(nt, 0), tSame(nt, 0);
    std::vector<std::vector<double>> tE(nt), tLen(nt);
    for (size_t i = 0; i < n; ++i) {
      if (!coat.present[i]) continue;
      const uint32_t t = coat.tract[i];
      ++tf[t];
      tE[t].push_back(elev[i] * 180 / M_PI);
      tLen[t].push_back(coat.params[i].totalLength());
      if (i < cr.featherPenetrations.size() && cr.featherPenetrations[i]) {
        tPen[t] += cr.featherPenetrations[i];
        ++tPenF[t];
      }
    }
    std::map<std::pair<uint32_t, uint32_t>, size_t> cross;
    for (const auto& q : cr.featherPairs) {
      const uint32_t ta = coat.tract[q.a], tb = coat.tract[q.b];
      tPairs[ta] += q.pairs;
      if (tb != ta)
        tPairs[tb] += q.pairs;
      else
        tSame[ta] += q.pairs;
      cross[{std::min(ta, tb), std::max(ta, tb)}] += q.pairs;
    }
    for (const auto& q : up) {
      tUp[coat.tract[q.a]] += q.pairs;
      if (coat.tract[q.b] != coat.tract[q.a]) tUp[coat.tract[q.b]] += q.pairs;
    }
    for (const auto& q : pp) {
      tPp[coat.tract[q.a]] += q.pairs;
      if (coat.tract[q.b] != coat.tract[q.a]) tPp[coat.tract[q.b]] += q.pairs;
    }
    std::printf("\n%-16s %5s %6s %6s %6s %6s %8s %8s %8s %8s %7s %5s %6s %6s\n", "tract", "n", "len", "e10", "e50",
                "e90", "pairs", "within", "proxy", "unpack", "pen", "penF", "area", "cover");
    double areaAll = 0;
    for (const auto& t : tracts)
      for (uint32_t f : t.faces) areaAll += skin.faceAreas[f];
    for (size_t t = 0; t < nt; ++t) {
      coat::CheckOptions cc;
      cc.seed = co.seed;
      cc.intersections = cc.penetrations = false;
      cc.coverageSamples = 4000;
      const double cov = cover ? coat::check(skin, tracts[t].faces, packedMesh, cc).coverage : NAN;
      double area = 0;
      for (uint32_t f : tracts[t].faces) area += skin.faceAreas[f];
      std::printf("%-16s %5zu %6.3f %6.1f %6.1f %6.1f %8zu %8zu %8zu %8zu %7zu %5zu %6.3f %6.3f\n",
                  tracts[t].name.c_str(), tf[t], pct(tLen[t], 0.5), pct(tE[t], 0.1), pct(tE[t], 0.5), pct(tE[t], 0.9),
                  tPairs[t], tSame[t], tPp[t], tUp[t], tPen[t], tPenF[t], area / areaAll, cov);
    }
    // Uncovered samples per tract by the direction of the skin normal (dominant axis, sign).
    std::printf("\nuncovered coverage samples by tract and normal direction (+x forward, +y up, +z left wing):\n");
    const char* dn[6] = {"+x", "-x", "+y", "-y", "+z", "-z"};
    for (size_t t = 0; t < nt; ++t) {
      size_t u[6] = {0, 0, 0, 0, 0, 0}, sm[6] = {0, 0, 0, 0, 0, 0};
      for (uint32_t f : tracts[t].faces) {
        if (f >= cr.faceSamples.size()) continue;
        const glm::dvec3 nn = skin.faceNormals[f];
        int ax = 0;
        for (int q = 1; q < 3; ++q)
          if (std::abs(nn[q]) > std::abs(nn[ax])) ax = q;
        const int d = 2 * ax + (nn[ax] < 0 ? 1 : 0);
        u[d] += cr.faceUncovered[f];
        sm[d] += cr.faceSamples[f];
      }
      std::printf("  %-16s", tracts[t].name.c_str());
      for (int d = 0; d < 6; ++d) std::printf("  %s %4zu/%-5zu", dn[d], u[d], sm[d]);
      std::printf("\n");
    }

    std::vector<std::pair<size_t, std::pair<uint32_t, uint32_t>>> cs;
    for (const auto& [k, v] : cross) cs.push_back({v, k});
    std::sort(cs.rbegin(), cs.rend());
    std::printf("\ntract pairs with the most intersecting pairs:\n");
    for (int k = 0; k < top && k < static_cast<int>(cs.size()); ++k)
      std::printf("  %-16s x %-16s %8zu\n", tracts[cs[k].second.first].name.c_str(),
                  tracts[cs[k].second.second].name.c_str(), cs[k].first);

    // Feather pairs: how far apart in layer order, which one is on top.
    std::vector<uint32_t> pos(n, UINT32_MAX);
    for (size_t k = 0; k < pr.order.size(); ++k) pos[pr.order[k]] = static_cast<uint32_t>(k);
    std::vector<coat::FeatherPairCount> fps = cr.featherPairs;
    std::sort(fps.begin(), fps.end(), [](const auto& a, const auto& b) { return a.pairs > b.pairs; });
    std::printf("\nfeather pairs with the most intersecting pairs (a below b in layer order):\n");
    for (int k = 0; k < top && k < static_cast<int>(fps.size()); ++k) {
      uint32_t a = fps[k].a, b = fps[k].b;
      if (pos[a] > pos[b]) std::swap(a, b);
      std::printf("  %5u (%s, e %.1f, len %.3f) under %5u (%s, e %.1f, len %.3f): %u pairs, dist %.3f\n", a,
                  tracts[coat.tract[a]].name.c_str(), elev[a] * 180 / M_PI, coat.params[a].totalLength(), b,
                  tracts[coat.tract[b]].name.c_str(), elev[b] * 180 / M_PI, coat.params[b].totalLength(), fps[k].pairs,
                  glm::length(coat.frames[a].origin - coat.frames[b].origin));
    }
    std::vector<std::pair<uint32_t, uint32_t>> pens;
    for (uint32_t i = 0; i < cr.featherPenetrations.size(); ++i)
      if (cr.featherPenetrations[i]) pens.push_back({cr.featherPenetrations[i], i});
    std::sort(pens.rbegin(), pens.rend());
    std::printf("\nfeathers with the most penetrating vertices:\n");
    for (int k = 0; k < top && k < static_cast<int>(pens.size()); ++k) {
      const uint32_t i = pens[k].second;
      std::printf("  %5u (%s, e %.1f, len %.3f, age %.2f): %u vertices\n", i, tracts[coat.tract[i]].name.c_str(),
                  elev[i] * 180 / M_PI, coat.params[i].totalLength(), coat.age[i], pens[k].first);
    }
    return 0;
  } catch (const Error& e) {  // bad input: the scene, an argument (the project's exit code 2)
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
