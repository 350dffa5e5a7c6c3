// glTF 2.0 writer (Khronos glTF 2.0 specification; KHR_materials_anisotropy) through tinygltf.
// Layout (docs/export.md): one node per frame holding one mesh: the skin primitive, then one primitive
// per feather material with the coat's vane cards and shafts. A frame range animates each frame node's
// scale with STEP samplers: 1 from its time to the next frame's, 0 elsewhere (a flipbook, which keeps
// changing topology, moult included, valid where morph targets would need a fixed vertex count).
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <ostream>
#include <sstream>
#include <streambuf>

#include "frames.hpp"
#include "pteryla/core/atomic_file.hpp"
#include "pteryla/core/error.hpp"

namespace pteryla::exchange::detail {
namespace {

// An output stream buffer that appends to an AtomicFile, unbuffered: tinygltf writes the JSON and the
// binary chunk in a few large pieces.
struct FileStreamBuf : std::streambuf {
  AtomicFile& file;
  size_t bytes = 0;
  explicit FileStreamBuf(AtomicFile& f) : file(f) {}
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    file.write(s, size_t(n));
    bytes += size_t(n);
    return n;
  }
  int_type overflow(int_type c) override {
    if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
    const char ch = traits_type::to_char_type(c);
    file.write(&ch, 1);
    ++bytes;
    return c;
  }
};

}  // namespace

namespace {

constexpr double kAnisotropyStrength = 0.8;  // barbs: strong, along the tangent

struct Builder {
  tinygltf::Model model;
  std::vector<unsigned char>& data() { return model.buffers[0].data; }

  int view(const void* bytes, size_t n, int target) {
    auto& d = data();
    while (d.size() % 4) d.push_back(0);
    tinygltf::BufferView v;
    v.buffer = 0;
    v.byteOffset = d.size();
    v.byteLength = n;
    v.target = target;
    const auto* p = static_cast<const unsigned char*>(bytes);
    d.insert(d.end(), p, p + n);
    model.bufferViews.push_back(v);
    return int(model.bufferViews.size() - 1);
  }

  // Float accessor of `comps` components per element; with bounds, min and max per component.
  int floats(const std::vector<float>& v, int comps, int type, bool bounds, int target = TINYGLTF_TARGET_ARRAY_BUFFER) {
    tinygltf::Accessor a;
    a.bufferView = view(v.data(), v.size() * sizeof(float), target);
    a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    a.count = v.size() / size_t(comps);
    a.type = type;
    if (bounds) {
      a.minValues.assign(size_t(comps), 0.0);
      a.maxValues.assign(size_t(comps), 0.0);
      for (int c = 0; c < comps; ++c) {
        float lo = v[size_t(c)], hi = v[size_t(c)];
        for (size_t i = size_t(c); i < v.size(); i += size_t(comps)) {
          lo = std::min(lo, v[i]);
          hi = std::max(hi, v[i]);
        }
        a.minValues[size_t(c)] = lo;
        a.maxValues[size_t(c)] = hi;
      }
    }
    model.accessors.push_back(a);
    return int(model.accessors.size() - 1);
  }

  int indices(const std::vector<uint32_t>& idx) {
    tinygltf::Accessor a;
    a.bufferView = view(idx.data(), idx.size() * 4, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    a.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    a.count = idx.size();
    a.type = TINYGLTF_TYPE_SCALAR;
    model.accessors.push_back(a);
    return int(model.accessors.size() - 1);
  }
};

glm::vec3 unitOr(const glm::vec3& v, const glm::vec3& fallback) {
  const float l = glm::length(v);
  return l > 1e-20f && std::isfinite(l) ? v / l : fallback;
}

// A unit vector perpendicular to unit n.
glm::vec3 anyPerpendicular(const glm::vec3& n) {
  const glm::vec3 a = std::fabs(n.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  return glm::normalize(glm::cross(n, a));
}

// One primitive from the triangles `tris` (indices into m.indices / 3) of `m`, vertices compacted in
// first-use order. `feathers` non-null adds the per-feather attributes.
tinygltf::Primitive primitive(Builder& b, const TriMesh& m, const std::vector<uint32_t>& tris, int material,
                              const std::vector<FeatherRecord>* feathers, bool texcoords) {
  std::vector<int64_t> remap(m.positions.size(), -1);
  std::vector<uint32_t> order, idx;
  idx.reserve(tris.size() * 3);
  if (!feathers) {  // the skin keeps its vertex order (a host's poses and weights index it)
    for (uint32_t v = 0; v < m.positions.size(); ++v) {
      remap[v] = v;
      order.push_back(v);
    }
  }
  for (uint32_t t : tris)
    for (int c = 0; c < 3; ++c) {
      const uint32_t v = m.indices[3 * size_t(t) + size_t(c)];
      if (remap[v] < 0) {
        remap[v] = int64_t(order.size());
        order.push_back(v);
      }
      idx.push_back(uint32_t(remap[v]));
    }
  const size_t n = order.size();
  std::vector<float> pos(3 * n), nrm(3 * n), tan, uv, col, fid, tract, layer, age;
  const bool hasN = !m.normals.empty(), hasT = !m.tangents.empty() && feathers;
  const bool hasUv = texcoords && !m.uvGlobal.empty(), hasA = !m.alpha.empty() && feathers;
  if (hasT) tan.resize(4 * n);
  if (hasUv) uv.resize(2 * n);
  if (hasA) col.resize(4 * n);
  if (feathers) {
    fid.resize(n);
    tract.resize(n);
    layer.resize(n);
    age.resize(n);
  }
  for (size_t i = 0; i < n; ++i) {
    const uint32_t v = order[i];
    for (int c = 0; c < 3; ++c) pos[3 * i + size_t(c)] = m.positions[v][c];
    const glm::vec3 nn = hasN ? unitOr(m.normals[v].get(), glm::vec3(0, 0, 1)) : glm::vec3(0, 0, 1);
    for (int c = 0; c < 3; ++c) nrm[3 * i + size_t(c)] = nn[c];
    if (hasT) {
      // glTF wants a unit tangent; the barb direction made orthogonal to the normal.
      const glm::vec3 tv = m.tangents[v];
      glm::vec3 t = tv - glm::dot(tv, nn) * nn;
      t = unitOr(t, anyPerpendicular(nn));
      for (int c = 0; c < 3; ++c) tan[4 * i + size_t(c)] = t[c];
      tan[4 * i + 3] = 1.0f;
    }
    if (hasUv) {
      uv[2 * i] = m.uvGlobal[v].x;
      uv[2 * i + 1] = 1.0f - m.uvGlobal[v].y;  // glTF's v runs down the image; pteryla's tip is the top row
    }
    if (hasA) {
      col[4 * i] = col[4 * i + 1] = col[4 * i + 2] = 1.0f;
      col[4 * i + 3] = std::clamp(static_cast<float>(m.alpha[v]), 0.0f, 1.0f);
    }
    if (feathers) {
      const uint32_t f = m.featherId.empty() ? 0 : m.featherId[v];
      const FeatherRecord& r = (*feathers)[f];
      fid[i] = float(r.id);
      tract[i] = float(r.tract);
      layer[i] = float(r.layer);
      age[i] = r.age;
    }
  }
  tinygltf::Primitive p;
  p.mode = TINYGLTF_MODE_TRIANGLES;
  p.material = material;
  p.attributes["POSITION"] = b.floats(pos, 3, TINYGLTF_TYPE_VEC3, true);
  p.attributes["NORMAL"] = b.floats(nrm, 3, TINYGLTF_TYPE_VEC3, false);
  if (hasT) p.attributes["TANGENT"] = b.floats(tan, 4, TINYGLTF_TYPE_VEC4, false);
  if (hasUv) p.attributes["TEXCOORD_0"] = b.floats(uv, 2, TINYGLTF_TYPE_VEC2, false);
  if (hasA) p.attributes["COLOR_0"] = b.floats(col, 4, TINYGLTF_TYPE_VEC4, false);
  if (feathers) {
    p.attributes["_FEATHER_ID"] = b.floats(fid, 1, TINYGLTF_TYPE_SCALAR, false);
    p.attributes["_TRACT"] = b.floats(tract, 1, TINYGLTF_TYPE_SCALAR, false);
    p.attributes["_LAYER"] = b.floats(layer, 1, TINYGLTF_TYPE_SCALAR, false);
    p.attributes["_AGE"] = b.floats(age, 1, TINYGLTF_TYPE_SCALAR, false);
  }
  p.indices = b.indices(idx);
  return p;
}

tinygltf::Value numbers(const std::vector<double>& v) {
  tinygltf::Value::Array a;
  for (double x : v) a.emplace_back(x);
  return tinygltf::Value(std::move(a));
}

}  // namespace

size_t writeGltf(const ExportScene& s, const std::string& path, bool binary) {
  Builder b;
  tinygltf::Model& model = b.model;
  model.asset.version = "2.0";
  model.asset.generator = "pteryla 0.1.0";
  model.buffers.resize(1);
  model.extensionsUsed.push_back("KHR_materials_anisotropy");

  // Materials: 0 = skin, 1 + k = feather material k.
  {
    tinygltf::Material skin;
    skin.name = "skin";
    skin.pbrMetallicRoughness.baseColorFactor = {s.skinColor.x, s.skinColor.y, s.skinColor.z, 1.0};
    skin.pbrMetallicRoughness.metallicFactor = 0.0;
    skin.pbrMetallicRoughness.roughnessFactor = 0.8;
    model.materials.push_back(skin);
  }
  tinygltf::Sampler sampler;
  sampler.magFilter = TINYGLTF_TEXTURE_FILTER_LINEAR;
  sampler.minFilter = TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_LINEAR;
  sampler.wrapS = sampler.wrapT = TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
  // Materials that use the same picture (blends of key feathers carry their heaviest part's) share one
  // image and texture.
  std::map<std::vector<unsigned char>, int> textureOf;
  for (const pipeline::CoatMaterial& cm : s.materials) {
    tinygltf::Material m;
    m.name = cm.name;
    m.doubleSided = true;
    m.alphaMode = "BLEND";
    m.pbrMetallicRoughness.metallicFactor = 0.0;
    m.pbrMetallicRoughness.roughnessFactor = 0.6;
    std::vector<unsigned char> bytes;
    std::string mime;
    if (materialImage(cm, bytes, mime) && textureOf.count(bytes)) {
      m.pbrMetallicRoughness.baseColorTexture.index = textureOf.at(bytes);
      m.pbrMetallicRoughness.baseColorFactor = {1.0, 1.0, 1.0, 1.0};
    } else if (!bytes.empty()) {
      if (model.samplers.empty()) model.samplers.push_back(sampler);
      tinygltf::Image img;
      img.name = cm.name;
      img.mimeType = mime;
      img.bufferView = b.view(bytes.data(), bytes.size(), 0);
      model.images.push_back(img);
      tinygltf::Texture tex;
      tex.source = int(model.images.size() - 1);
      tex.sampler = 0;
      model.textures.push_back(tex);
      m.pbrMetallicRoughness.baseColorTexture.index = int(model.textures.size() - 1);
      m.pbrMetallicRoughness.baseColorFactor = {1.0, 1.0, 1.0, 1.0};
      textureOf.emplace(std::move(bytes), m.pbrMetallicRoughness.baseColorTexture.index);
    } else {
      m.pbrMetallicRoughness.baseColorFactor = {cm.baseColor.x, cm.baseColor.y, cm.baseColor.z, 1.0};
    }
    tinygltf::Value::Object aniso;
    aniso["anisotropyStrength"] = tinygltf::Value(kAnisotropyStrength);
    aniso["anisotropyRotation"] = tinygltf::Value(0.0);  // along TANGENT: the barb direction
    m.extensions["KHR_materials_anisotropy"] = tinygltf::Value(std::move(aniso));
    model.materials.push_back(m);
  }

  tinygltf::Scene scene;
  scene.name = "pteryla";
  const bool animated = s.frames.size() > 1;
  std::vector<double> times;
  for (size_t k = 0; k < s.frames.size(); ++k) {
    const ExportFrame& f = s.frames[k];
    tinygltf::Mesh mesh;
    mesh.name = "coat_" + std::to_string(k);
    if (!f.skin.empty()) {
      std::vector<uint32_t> all(f.skin.triangleCount());
      for (size_t t = 0; t < all.size(); ++t) all[t] = uint32_t(t);
      mesh.primitives.push_back(primitive(b, f.skin, all, 0, nullptr, false));
    }
    std::vector<std::vector<uint32_t>> byMaterial(s.materials.size());
    for (const pipeline::CoatDrawRange& r : f.ranges) {
      const uint32_t mat = r.material < s.materials.size() ? r.material : 0;
      for (uint32_t t = r.firstIndex / 3; t < (r.firstIndex + r.indexCount) / 3; ++t)
        if (!collapsed(&f.coat.indices[3 * size_t(t)])) byMaterial[mat].push_back(t);
    }
    for (size_t m = 0; m < byMaterial.size(); ++m)
      if (!byMaterial[m].empty())
        mesh.primitives.push_back(primitive(b, f.coat, byMaterial[m], int(m + 1), &f.feathers, true));
    if (mesh.primitives.empty()) throw Error("nothing to export: the frame has no skin and no feathers", path);
    model.meshes.push_back(mesh);
    tinygltf::Node node;
    node.name = animated ? "frame_" + std::to_string(k) : "pteryla";
    node.mesh = int(model.meshes.size() - 1);
    tinygltf::Value::Object extras;
    extras["time"] = tinygltf::Value(f.time);
    node.extras = tinygltf::Value(std::move(extras));
    model.nodes.push_back(node);
    scene.nodes.push_back(int(model.nodes.size() - 1));
    times.push_back(double(k) / s.fps);
  }
  if (animated) {
    tinygltf::Animation anim;
    anim.name = "frames";
    const size_t n = s.frames.size();
    for (size_t k = 0; k < n; ++k) {
      // Keys at 0 (hidden unless k = 0), t_k (shown), t_k+1 (hidden again).
      std::vector<float> in, out;
      if (k > 0) {
        in.push_back(0.0f);
        out.insert(out.end(), {0, 0, 0});
      }
      in.push_back(float(times[k]));
      out.insert(out.end(), {1, 1, 1});
      if (k + 1 < n) {
        in.push_back(float(times[k + 1]));
        out.insert(out.end(), {0, 0, 0});
      }
      for (size_t i = 1; i < in.size(); ++i)
        if (!(in[i] > in[i - 1])) throw Error("frames closer than float time resolution; lower --fps", path, "--fps");
      tinygltf::AnimationSampler sm;
      sm.input = b.floats(in, 1, TINYGLTF_TYPE_SCALAR, true, 0);
      sm.output = b.floats(out, 3, TINYGLTF_TYPE_VEC3, false, 0);
      sm.interpolation = "STEP";
      anim.samplers.push_back(sm);
      tinygltf::AnimationChannel ch;
      ch.sampler = int(anim.samplers.size() - 1);
      ch.target_node = int(k);
      ch.target_path = "scale";
      anim.channels.push_back(ch);
      if (k > 0) model.nodes[k].scale = {0.0, 0.0, 0.0};  // the static pose shows frame 0
    }
    model.animations.push_back(anim);
  }
  model.scenes.push_back(scene);
  model.defaultScene = 0;

  tinygltf::Value::Object pteryla;
  tinygltf::Value::Array tracts;
  for (const auto& t : s.tractNames) tracts.emplace_back(t);
  pteryla["tracts"] = tinygltf::Value(std::move(tracts));
  std::vector<double> sceneTimes;
  for (const auto& f : s.frames) sceneTimes.push_back(f.time);
  pteryla["times"] = numbers(sceneTimes);
  pteryla["fps"] = tinygltf::Value(s.fps);
  pteryla["attributes"] =
      tinygltf::Value(std::string("_FEATHER_ID feather index, _TRACT index into tracts, _LAYER packing order (0 "
                                  "bottom), _AGE growth age; docs/export.md"));
  tinygltf::Value::Object assetExtras;
  assetExtras["pteryla"] = tinygltf::Value(std::move(pteryla));
  model.asset.extras = tinygltf::Value(std::move(assetExtras));

  // Serialized straight into the temporary file: no copy of the buffer in a string stream. A failed write
  // throws from AtomicFile; badbit in the mask lets that exception out of the ostream unchanged.
  AtomicFile file(path);
  FileStreamBuf buf(file);
  std::ostream os(&buf);
  os.exceptions(std::ios::badbit);
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToStream(&model, os, /*prettyPrint=*/!binary, binary) || !os)
    throw Error("the glTF serializer failed", path);
  file.commit();
  return buf.bytes;
}

}  // namespace pteryla::exchange::detail
