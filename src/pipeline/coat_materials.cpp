// The coat's materials: one per feather definition, then one per distinct quantised blend of key
// feathers' looks (coat_materials.hpp; issue #30 item 2).
#include "coat_materials.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <sstream>
#include <utility>

#include "pteryla/core/error.hpp"
#include "pteryla/core/paths.hpp"

namespace pteryla::pipeline {

bool isDownName(const std::string& name) { return name.find("down") != std::string::npos; }

bool sameLook(const CoatMaterial& a, const CoatMaterial& b) {
  return a.texture == b.texture && a.alphaTexture == b.alphaTexture && a.pattern == b.pattern &&
         a.baseColor == b.baseColor && a.uv == b.uv && a.brdfD == b.brdfD && a.brdfH == b.brdfH && a.blend == b.blend &&
         isDownName(a.name) == isDownName(b.name);
}

CoatMaterial definitionMaterial(const std::string& name, const feather::FeatherParams& p) {
  CoatMaterial m;
  m.name = name;
  auto resolve = [&](const std::string& t) { return t.empty() ? t : resolveRelative(p.sourceFile, t); };
  m.texture = resolve(p.material.texture);
  m.alphaTexture = resolve(p.material.alphaTexture);
  m.pattern = p.material.pattern;
  if (p.material.baseColor) m.baseColor = glm::vec3(*p.material.baseColor);
  m.uv = p.material.uv;
  m.brdfD = p.material.brdfD;
  m.brdfH = p.material.brdfH;
  return m;
}

std::vector<int> quantiseWeights(const std::vector<double>& weights, int steps) {
  PTERYLA_CHECK(steps > 0, "quantiseWeights needs a positive step count");
  const double sum = std::accumulate(weights.begin(), weights.end(), 0.0);
  PTERYLA_CHECK(sum > 0 && std::isfinite(sum), "quantiseWeights needs weights with a positive sum");
  std::vector<int> q(weights.size());
  std::vector<double> rest(weights.size());
  int used = 0;
  for (size_t k = 0; k < weights.size(); ++k) {
    const double x = std::max(weights[k], 0.0) / sum * steps;
    q[k] = static_cast<int>(std::floor(x));
    rest[k] = x - q[k];
    used += q[k];
  }
  std::vector<size_t> order(weights.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return rest[a] > rest[b]; });
  for (size_t k = 0; used < steps && k < order.size(); ++k, ++used) ++q[order[k]];
  return q;
}

namespace {

std::string fraction(int q, int steps) {
  const int g = std::gcd(q, steps);
  return std::to_string(q / g) + "/" + std::to_string(steps / g);
}

}  // namespace

CoatMaterials coatMaterials(const std::vector<std::string>& names, const coat::FeatherLibrary& library,
                            const coat::CoatFeathers& coat) {
  CoatMaterials out;
  std::map<std::string, uint32_t> index;
  for (const std::string& name : names) {
    index[name] = static_cast<uint32_t>(out.materials.size());
    out.materials.push_back(definitionMaterial(name, library.at(name)));
  }
  // Definitions that look alike blend as one: each stands for the first of its look.
  std::vector<uint32_t> look(names.size());
  for (uint32_t m = 0; m < names.size(); ++m) {
    look[m] = m;
    for (uint32_t e = 0; e < m; ++e)
      if (sameLook(out.materials[e], out.materials[m])) {
        look[m] = e;
        break;
      }
  }
  auto indexOf = [&](const std::string& name) {
    const auto it = index.find(name);
    return it == index.end() ? 0u : it->second;
  };
  const bool haveBlends = coat.keyBlend.size() == coat.size();
  std::map<std::vector<std::pair<uint32_t, int>>, uint32_t> blends;
  out.featherMaterial.resize(coat.size());
  std::vector<double> w;
  for (size_t i = 0; i < coat.size(); ++i) {
    const uint32_t own = indexOf(coat.params[i].name);
    out.featherMaterial[i] = own;
    if (!haveBlends || coat.keyBlend[i].count < 2) continue;
    const coat::KeyBlend& kb = coat.keyBlend[i];
    w.assign(kb.weight.begin(), kb.weight.begin() + kb.count);
    const std::vector<int> q = quantiseWeights(w, kMaterialWeightSteps);
    std::map<uint32_t, int> byLook;
    std::map<uint32_t, std::string> keyOfLook;  // the first of this feather's keys with that look
    for (size_t k = 0; k < kb.count; ++k) {
      PTERYLA_CHECK(kb.key[k] < coat.keyNames.size(), "key blend names a missing key feather");
      if (q[k] == 0) continue;
      const std::string& key = coat.keyNames[kb.key[k]];
      byLook[look[indexOf(key)]] += q[k];
      keyOfLook.emplace(look[indexOf(key)], key);
    }
    if (byLook.size() < 2) continue;  // one look: the definition's own material
    std::vector<std::pair<uint32_t, int>> key(byLook.begin(), byLook.end());
    const auto [it, added] = blends.try_emplace(key, static_cast<uint32_t>(out.materials.size()));
    out.featherMaterial[i] = it->second;
    if (!added) continue;
    // The blended material: parts and weights for renderers that blend; for the others (exporters,
    // hosts) the heaviest part's textures and the blended base colour.
    CoatMaterial m;
    std::ostringstream name;
    glm::vec3 base(0.0f);
    size_t top = 0;
    for (size_t k = 0; k < key.size(); ++k) {
      const CoatMaterial& part = out.materials[key[k].first];
      const double wk = double(key[k].second) / kMaterialWeightSteps;
      m.blend.push_back({key[k].first, wk});
      base += part.baseColor * static_cast<float>(wk);
      if (key[k].second > key[top].second) top = k;
      name << (k ? " + " : "") << keyOfLook[key[k].first] << " " << fraction(key[k].second, kMaterialWeightSteps);
    }
    const CoatMaterial& heaviest = out.materials[key[top].first];
    m.name = name.str();
    m.texture = heaviest.texture;
    m.alphaTexture = heaviest.alphaTexture;
    m.pattern = heaviest.pattern;
    m.uv = heaviest.uv;
    m.brdfD = heaviest.brdfD;
    m.brdfH = heaviest.brdfH;
    m.baseColor = base;
    out.materials.push_back(std::move(m));
  }
  return out;
}

}  // namespace pteryla::pipeline
