// Key-feather interpolation over a tract. Streit 2003, 6.2 (key feathers, 2D Delaunay triangulation of the
// key follicles in parameter space, barycentric weights u = area(p,p2,p3)/area(p1,p2,p3), ...) and 9.2.1
// (tract boundaries carry key feathers). The blend itself is feather::blendFeathers (5.2.4).
#include "pteryla/coat/key_feathers.hpp"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "pteryla/core/error.hpp"
#include "pteryla/core/rng.hpp"
#include "pteryla/feather/interpolate.hpp"

namespace pteryla::coat {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<uint32_t, K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb>;
using Delaunay = CGAL::Delaunay_triangulation_2<K, Tds>;

constexpr uint64_t kJitterStream = 0x5CA1E;  // decorrelates the jitter from other per-follicle draws

double cross2(const glm::dvec2& a, const glm::dvec2& b) { return a.x * b.y - a.y * b.x; }

// Closest point on segment ab: parameter t in [0,1] and squared distance.
double segmentParam(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& p, double& dist2) {
  const glm::dvec2 d = b - a;
  const double len2 = glm::dot(d, d);
  double t = len2 > 0 ? glm::dot(p - a, d) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  const glm::dvec2 q = a + t * d - p;
  dist2 = glm::dot(q, q);
  return t;
}

BlendWeights single(uint32_t k, bool inside) {
  BlendWeights w;
  w.key = {k, k, k};
  w.weight = {1, 0, 0};
  w.count = 1;
  w.inside = inside;
  return w;
}

// A weight of exactly (or within 1e-12 of) one collapses to that key.
BlendWeights collapse(BlendWeights w) {
  for (int i = 0; i < w.count; ++i)
    if (w.weight[static_cast<size_t>(i)] >= 1.0 - 1e-12) return single(w.key[static_cast<size_t>(i)], w.inside);
  return w;
}

}  // namespace

KeyTriangulation triangulateKeys(const std::vector<glm::dvec2>& keys) {
  KeyTriangulation out;
  out.keys = keys;
  const uint32_t n = static_cast<uint32_t>(keys.size());
  if (n < 2) return out;
  std::vector<std::pair<K::Point_2, uint32_t>> pts;
  pts.reserve(n);
  for (uint32_t i = 0; i < n; ++i) pts.emplace_back(K::Point_2(keys[i].x, keys[i].y), i);
  Delaunay dt;
  dt.insert(pts.begin(), pts.end());
  PTERYLA_CHECK_EQ(dt.number_of_vertices(), n, "triangulateKeys: key positions must be distinct");
  if (dt.dimension() == 2) {
    for (auto f = dt.finite_faces_begin(); f != dt.finite_faces_end(); ++f)
      out.triangles.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
    for (auto e = dt.finite_edges_begin(); e != dt.finite_edges_end(); ++e) {
      const auto f = e->first;
      const int i = e->second;
      if (!dt.is_infinite(f) && !dt.is_infinite(f->neighbor(i))) continue;
      uint32_t a = f->vertex(Delaunay::cw(i))->info(), b = f->vertex(Delaunay::ccw(i))->info();
      out.hullEdges.push_back({std::min(a, b), std::max(a, b)});
    }
    // Deterministic order independent of CGAL's internal storage.
    for (auto& t : out.triangles) std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    std::sort(out.triangles.begin(), out.triangles.end());
    std::sort(out.hullEdges.begin(), out.hullEdges.end());
  } else {
    // Collinear keys: the chain of keys sorted along the line.
    std::vector<uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    glm::dvec2 dir(0.0);
    for (uint32_t i = 1; i < n; ++i)
      if (glm::length(keys[i] - keys[0]) > glm::length(dir)) dir = keys[i] - keys[0];
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
      const double da = glm::dot(keys[a] - keys[0], dir), db = glm::dot(keys[b] - keys[0], dir);
      return da != db ? da < db : a < b;
    });
    for (uint32_t i = 0; i + 1 < n; ++i) out.hullEdges.push_back({order[i], order[i + 1]});
  }
  return out;
}

BlendWeights locateInKeys(const KeyTriangulation& tri, const glm::dvec2& p) {
  const auto& k = tri.keys;
  PTERYLA_CHECK(!k.empty(), "locateInKeys: no keys");
  if (k.size() == 1) return single(0, true);
  // Inside a triangle: the one whose smallest barycentric coordinate is largest.
  double bestMin = -std::numeric_limits<double>::infinity();
  BlendWeights best;
  for (const auto& t : tri.triangles) {
    const glm::dvec2 &a = k[t[0]], &b = k[t[1]], &c = k[t[2]];
    const double area = cross2(b - a, c - a);
    if (!(area > 0)) continue;
    const double u = cross2(b - p, c - p) / area;  // weight of a: area(p, b, c) / area(a, b, c)
    const double v = cross2(c - p, a - p) / area;  // weight of b: area(p, c, a) / area(a, b, c)
    const double w = 1.0 - u - v;
    const double m = std::min({u, v, w});
    if (m > bestMin) {
      bestMin = m;
      best.key = t;
      best.weight = {u, v, w};
      best.count = 3;
    }
  }
  if (!tri.triangles.empty() && bestMin >= -1e-12) {
    double sum = 0;
    for (auto& w : best.weight) sum += (w = std::max(w, 0.0));
    for (auto& w : best.weight) w /= sum;
    best.inside = true;
    return collapse(best);
  }
  // Outside the hull (or collinear keys): the nearest hull edge, clamped to its ends.
  double bestD = std::numeric_limits<double>::infinity();
  BlendWeights edge;
  for (const auto& e : tri.hullEdges) {
    double d2 = 0;
    const double t = segmentParam(k[e[0]], k[e[1]], p, d2);
    if (d2 < bestD) {
      bestD = d2;
      edge.key = {e[0], e[1], e[0]};
      edge.weight = {1.0 - t, t, 0.0};
      edge.count = 2;
    }
  }
  // Collinear keys: a point beside the chain is still "inside" when it projects inside it.
  edge.inside = tri.triangles.empty() && edge.weight[0] > 0 && edge.weight[1] > 0;
  return collapse(edge);
}

std::vector<KeyFeather> resolveKeyFeathers(const Follicles& follicles, const TractParameterization& param,
                                           const std::vector<KeyFeatherSpec>& specs, const FeatherLibrary& library,
                                           const std::string& tractName, const std::string& defaultFeather,
                                           const std::string& file) {
  std::vector<KeyFeather> keys;
  const std::string tractWhere = "tracts." + tractName;
  auto checkName = [&](const std::string& name, const std::string& element) {
    if (library.count(name)) return;
    std::string known;
    for (const auto& [n, p] : library) known += (known.empty() ? "" : ", ") + n;
    throw Error("unknown feather '" + name + "' (defined: " + (known.empty() ? "none" : known) + ")", file, element);
  };
  if (specs.empty()) {
    if (param.follicles.empty()) return keys;
    std::string name = defaultFeather;
    if (name.empty()) {
      if (library.size() != 1)
        throw Error("tract '" + tractName + "' has no key_feathers and no \"feather\", and the scene defines " +
                        std::to_string(library.size()) + " feathers: say which one it carries",
                    file, tractWhere);
      name = library.begin()->first;
    }
    checkName(name, tractWhere + ".feather");
    keys.push_back({param.follicles.front(), name});
    return keys;
  }
  for (const auto& s : specs) {
    const std::string element = s.element.empty() ? tractWhere + ".key_feathers" : s.element;
    checkName(s.feather, element + ".feather");
    if (param.follicles.empty())
      throw Error("key feather '" + s.feather + "' on tract '" + tractName + "', which has no follicles", file,
                  element);
    uint32_t chosen = UINT32_MAX;
    if (s.byFollicle) {
      for (uint32_t f : param.follicles)
        if (follicles.id[f] == s.follicleId) {
          chosen = f;
          break;
        }
      if (chosen == UINT32_MAX)
        throw Error("follicle id " + std::to_string(s.follicleId) + " is not a follicle of tract '" + tractName + "'",
                    file, element + ".follicle");
    } else {
      double best = std::numeric_limits<double>::infinity();
      for (uint32_t f : param.follicles) {
        const glm::dvec3 d = follicles.position[f] - s.at;
        const double d2 = glm::dot(d, d);
        if (d2 < best) best = d2, chosen = f;
      }
    }
    keys.push_back({chosen, s.feather});
  }
  // Distinct follicles and distinct (u,v).
  std::vector<glm::dvec2> uv(keys.size());
  for (size_t i = 0; i < keys.size(); ++i) {
    const auto it = std::lower_bound(param.follicles.begin(), param.follicles.end(), keys[i].follicle);
    uv[i] = param.follicleUv[static_cast<size_t>(it - param.follicles.begin())];
    for (size_t j = 0; j < i; ++j) {
      const std::string element = specs[i].element.empty() ? tractWhere + ".key_feathers" : specs[i].element;
      if (keys[j].follicle == keys[i].follicle)
        throw Error("key feathers '" + keys[j].feather + "' and '" + keys[i].feather + "' land on the same follicle " +
                        std::to_string(follicles.id[keys[i].follicle]) + " of tract '" + tractName + "'",
                    file, element);
      if (uv[j] == uv[i])
        throw Error("key feathers '" + keys[j].feather + "' and '" + keys[i].feather +
                        "' have the same (u,v) in tract '" + tractName + "' (the parameterization folds there)",
                    file, element);
    }
  }
  return keys;
}

std::vector<BlendWeights> tractBlendWeights(const TractParameterization& param, const std::vector<KeyFeather>& keys) {
  PTERYLA_CHECK_EQ(param.follicles.size(), param.follicleUv.size(), "parameterization arrays differ in size");
  std::vector<BlendWeights> out(param.follicles.size());
  if (param.follicles.empty()) return out;
  PTERYLA_CHECK(!keys.empty(), "tractBlendWeights: a tract with follicles needs key feathers");
  std::vector<glm::dvec2> keyUv(keys.size());
  std::vector<int32_t> keyAt(param.follicles.size(), -1);
  for (size_t i = 0; i < keys.size(); ++i) {
    const auto it = std::lower_bound(param.follicles.begin(), param.follicles.end(), keys[i].follicle);
    PTERYLA_CHECK(it != param.follicles.end() && *it == keys[i].follicle,
                  "key feather on a follicle outside its tract");
    const size_t slot = static_cast<size_t>(it - param.follicles.begin());
    keyUv[i] = param.follicleUv[slot];
    keyAt[slot] = static_cast<int32_t>(i);
  }
  const KeyTriangulation tri = triangulateKeys(keyUv);
  tbb::parallel_for(size_t(0), out.size(), [&](size_t i) {
    out[i] = keyAt[i] >= 0 ? single(static_cast<uint32_t>(keyAt[i]), true) : locateInKeys(tri, param.follicleUv[i]);
  });
  return out;
}

void scaleFeather(feather::FeatherParams& p, double s) {
  PTERYLA_CHECK(s > 0 && std::isfinite(s), "scaleFeather: scale must be positive");
  p.calamusLength *= s;
  p.rachisLength *= s;
  p.rachisWidth *= s;
  p.barbLength *= s;
  for (auto* prof : {&p.silhouette.left, &p.silhouette.right})
    for (auto& q : prof->points) q.y *= s;
  p.spacingBase *= s;
  p.spacingTip *= s;
  if (p.afterfeather) {
    auto after = std::make_shared<feather::FeatherParams>(*p.afterfeather);
    scaleFeather(*after, s);
    p.afterfeather = std::move(after);
  }
}

InterpolateStats interpolateCoatFeathers(const Follicles& follicles, const std::vector<TractKeys>& tracts,
                                         const FeatherLibrary& library, const InterpolateOptions& options,
                                         CoatFeathers& coat) {
  // Feather slot of every follicle: ascending follicle order over all tracts.
  struct Slot {
    uint32_t tract = UINT32_MAX;
    uint32_t local = 0;  // index in the tract's param.follicles
  };
  std::vector<Slot> slots(follicles.size());
  for (uint32_t t = 0; t < tracts.size(); ++t) {
    const TractParameterization* param = tracts[t].param;
    PTERYLA_CHECK_NE(param, nullptr, "interpolateCoatFeathers: tract without a parameterization");
    for (uint32_t k = 0; k < param->follicles.size(); ++k) {
      const uint32_t f = param->follicles[k];
      PTERYLA_CHECK(f < follicles.size(), "parameterization refers to a missing follicle");
      PTERYLA_CHECK_EQ(slots[f].tract, UINT32_MAX, "follicle parameterized by two tracts");
      slots[f] = {t, k};
    }
  }
  // Resolve key feather definitions and weights per tract.
  std::vector<std::vector<const feather::FeatherParams*>> keyParams(tracts.size());
  std::vector<std::vector<BlendWeights>> weights(tracts.size());
  for (size_t t = 0; t < tracts.size(); ++t) {
    for (const auto& k : tracts[t].keys) {
      const auto it = library.find(k.feather);
      if (it == library.end()) throw Error("unknown feather '" + k.feather + "'", {}, "key_feathers");
      keyParams[t].push_back(&it->second);
    }
    weights[t] = tractBlendWeights(*tracts[t].param, tracts[t].keys);
    if (!(tracts[t].scaleJitter >= 0 && tracts[t].scaleJitter < 1))
      throw Error("scale_jitter must be in [0, 1)", {}, "scale_jitter");
  }
  coat = CoatFeathers{};
  for (uint32_t f = 0; f < follicles.size(); ++f)
    if (slots[f].tract != UINT32_MAX) {
      coat.follicle.push_back(f);
      coat.tract.push_back(slots[f].tract);
    }
  const size_t n = coat.follicle.size();
  coat.params.resize(n);
  coat.frames.resize(n);
  coat.age.assign(n, 1.0);
  coat.present.assign(n, 1);
  coat.layerOrder.clear();
  // Key blends name feather definitions through one table for the whole coat.
  std::vector<std::vector<uint32_t>> keyName(tracts.size());
  for (size_t t = 0; t < tracts.size(); ++t)
    for (const auto& k : tracts[t].keys) {
      const auto it = std::find(coat.keyNames.begin(), coat.keyNames.end(), k.feather);
      keyName[t].push_back(static_cast<uint32_t>(it - coat.keyNames.begin()));
      if (it == coat.keyNames.end()) coat.keyNames.push_back(k.feather);
    }
  coat.keyBlend.assign(n, KeyBlend{});

  std::vector<uint8_t> kind(n, 0);  // 1 copied, 2 blended
  std::vector<uint8_t> outside(n, 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 16), [&](const tbb::blocked_range<size_t>& range) {
    std::vector<const feather::FeatherParams*> fs;
    std::vector<double> ws;
    for (size_t i = range.begin(); i != range.end(); ++i) {
      const uint32_t f = coat.follicle[i];
      const Slot s = slots[f];
      const BlendWeights& w = weights[s.tract][s.local];
      const auto& kp = keyParams[s.tract];
      outside[i] = !w.inside;
      FeatherFrame& fr = coat.frames[i];
      fr.origin = follicles.position[f];
      fr.normal = follicles.normal[f];
      // A valid right-handed frame until evaluateFrames() sets the surface direction.
      const glm::dvec3 other = std::abs(fr.normal.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
      fr.tangent = glm::normalize(glm::cross(other, fr.normal));
      fr.binormal = glm::cross(fr.normal, fr.tangent);
      // The weights blendFeathers uses: the positive ones, normalised.
      KeyBlend& kb = coat.keyBlend[i];
      kb.count = 0;
      double sum = 0;
      for (int j = 0; j < w.count; ++j)
        sum += w.weight[static_cast<size_t>(j)] > 0 ? w.weight[static_cast<size_t>(j)] : 0;
      for (int j = 0; j < w.count; ++j) {
        const size_t sj = static_cast<size_t>(j);
        if (!(w.weight[sj] > 0) && w.count > 1) continue;
        kb.key[kb.count] = keyName[s.tract][w.key[sj]];
        kb.weight[kb.count] = w.count == 1 ? 1.0 : w.weight[sj] / sum;
        ++kb.count;
      }
      if (w.count == 1) {
        coat.params[i] = *kp[w.key[0]];
        kind[i] = 1;
        if (tracts[s.tract].keys[w.key[0]].follicle == f) continue;  // key feathers stay exact
      } else {
        fs.clear();
        ws.clear();
        for (int j = 0; j < w.count; ++j) {
          fs.push_back(kp[w.key[static_cast<size_t>(j)]]);
          ws.push_back(w.weight[static_cast<size_t>(j)]);
        }
        coat.params[i] = feather::blendFeathers(fs, ws);
        kind[i] = 2;
      }
      const double jitter = tracts[s.tract].scaleJitter;
      if (jitter > 0)
        scaleFeather(coat.params[i],
                     1.0 + jitter * (2.0 * hashUniform(options.seed, follicles.id[f], kJitterStream) - 1.0));
    }
  });
  InterpolateStats st;
  st.feathers = n;
  for (size_t i = 0; i < n; ++i) {
    st.copied += kind[i] == 1;
    st.blended += kind[i] == 2;
    st.outsideHull += outside[i];
  }
  return st;
}

KeyFeatherSpec parseKeyFeather(JsonReader& r) {
  KeyFeatherSpec s;
  s.element = r.path();
  s.feather = r.string("feather");
  if (s.feather.empty()) r.fail("feather", "must name a feather");
  const bool hasF = r.has("follicle"), hasAt = r.has("at");
  if (hasF == hasAt)
    r.fail(hasF ? "at" : "feather", "a key feather needs exactly one of \"follicle\" (an id) or \"at\" ([x,y,z])");
  if (hasF) {
    s.byFollicle = true;
    s.follicleId = static_cast<uint64_t>(r.integer("follicle", 0, std::numeric_limits<int64_t>::max()));
  } else {
    s.at = r.vec3("at");
  }
  r.finish();
  return s;
}

std::vector<KeyFeatherSpec> parseKeyFeathers(JsonReader& tract) {
  std::vector<KeyFeatherSpec> out;
  if (!tract.has("key_feathers")) return out;
  if (!tract.json().at("key_feathers").is_array())
    tract.fail("key_feathers", "expected an array of key feather objects");
  for (auto& item : tract.objects("key_feathers")) out.push_back(parseKeyFeather(item));
  return out;
}

TractFeatherOptions parseTractFeatherOptions(JsonReader& tract) {
  TractFeatherOptions o;
  if (tract.has("parameterization")) {
    JsonReader p = tract.object("parameterization");
    o.parameterization = parseParameterization(p);
  }
  o.keys = parseKeyFeathers(tract);
  o.feather = tract.string("feather", "");
  o.scaleJitter = tract.number("scale_jitter", 0.0, 0.0, 0.99);
  return o;
}

}  // namespace pteryla::coat
