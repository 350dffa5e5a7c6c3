#include "handles.hpp"

#include <algorithm>
#include <cstdio>

#include "actions.hpp"
#include "pteryla/core/error.hpp"
#include "scene_edit.hpp"

namespace pteryla::viewer {

using pipeline::Scene;

const char* handleKindName(HandleKind k) {
  switch (k) {
    case HandleKind::Control:
      return "control";
    case HandleKind::Brush:
      return "brush";
    case HandleKind::Vector:
      return "vector";
    case HandleKind::KeyFeather:
      return "key feather";
    case HandleKind::Pinned:
      return "pinned follicle";
  }
  return "handle";
}

namespace {

bool hasPoint(const Json& j, const char* key) {
  return j.is_object() && j.contains(key) && j[key].is_array() && j[key].size() == 3;
}

// The JSON object a handle edits, or nullptr.
Json* entry(Scene& s, const Handle& h) {
  auto at = [](Json& list, size_t i) -> Json* { return list.is_array() && i < list.size() ? &list[i] : nullptr; };
  switch (h.kind) {
    case HandleKind::Control:
      return at(s.controls, h.index);
    case HandleKind::Brush:
      return s.packing.contains("styling") ? at(s.packing["styling"], h.index) : nullptr;
    case HandleKind::Vector:
      return s.directions.contains("vectors") ? at(s.directions["vectors"], h.index) : nullptr;
    case HandleKind::KeyFeather:
    case HandleKind::Pinned: {
      if (h.tract >= s.tracts.size() || !s.tracts[h.tract].is_object()) return nullptr;
      const char* key = h.kind == HandleKind::KeyFeather ? "key_feathers" : "pinned";
      return s.tracts[h.tract].contains(key) ? at(s.tracts[h.tract][key], h.index) : nullptr;
    }
  }
  return nullptr;
}

const char* pointKey(HandleKind k) { return k == HandleKind::Brush ? "center" : "at"; }

bool isHandle(const Json& j, HandleKind k) {
  if (!hasPoint(j, pointKey(k))) return false;
  return k != HandleKind::Brush || j.value("select", "") == "sphere";
}

[[noreturn]] void gone(const Scene& s, const Handle& h) {
  throw Error(std::string("the ") + handleKindName(h.kind) + " " + std::to_string(h.index) + " is gone", s.file,
              handleKindName(h.kind));
}

}  // namespace

std::vector<Handle> sceneHandles(const Scene& s) {
  std::vector<Handle> out;
  auto list = [&](const Json& l, HandleKind k, size_t tract) {
    if (!l.is_array()) return;
    for (size_t i = 0; i < l.size(); ++i)
      if (isHandle(l[i], k)) out.push_back({k, i, tract, glm::vec3(actions::jsonVec3(l[i][pointKey(k)]))});
  };
  list(s.controls, HandleKind::Control, 0);
  if (s.packing.contains("styling")) list(s.packing["styling"], HandleKind::Brush, 0);
  if (s.directions.contains("vectors")) list(s.directions["vectors"], HandleKind::Vector, 0);
  for (size_t t = 0; t < s.tracts.size(); ++t) {
    if (!s.tracts[t].is_object()) continue;
    if (s.tracts[t].contains("key_feathers")) list(s.tracts[t]["key_feathers"], HandleKind::KeyFeather, t);
    if (s.tracts[t].contains("pinned")) list(s.tracts[t]["pinned"], HandleKind::Pinned, t);
  }
  return out;
}

std::optional<Handle> findHandle(const Scene& s, const Handle& h) {
  for (const Handle& x : sceneHandles(s))
    if (x == h) return x;
  return std::nullopt;
}

std::string handleReadout(const Scene& s, const Handle& h) {
  Scene copy = s;
  const Json* j = entry(copy, h);
  if (!j) return "";
  char buf[160];
  std::string out = std::string(handleKindName(h.kind)) + " " + std::to_string(h.index);
  if (j->contains("name") && (*j)["name"].is_string()) out += " '" + (*j)["name"].get<std::string>() + "'";
  if (h.kind == HandleKind::KeyFeather || h.kind == HandleKind::Pinned) out += "\ntract: " + tractName(s, h.tract);
  if (j->contains("feather") && (*j)["feather"].is_string()) out += "\nfeather: " + (*j)["feather"].get<std::string>();
  std::snprintf(buf, sizeof buf, "\nat: %.3f %.3f %.3f", double(h.at.x), double(h.at.y), double(h.at.z));
  out += buf;
  if (j->contains("radius") && (*j)["radius"].is_number()) {
    std::snprintf(buf, sizeof buf, "\nradius: %.3g", (*j)["radius"].get<double>());
    out += buf;
  }
  for (const char* k : {"elevation_deg", "min_elevation_deg"})
    if (j->contains(k) && (*j)[k].is_number()) {
      std::snprintf(buf, sizeof buf, "\n%s: %.3g", k, (*j)[k].get<double>());
      out += buf;
    }
  out += "\ndrag to move, click then Delete to remove";
  return out;
}

void moveHandle(Document& d, const Handle& h, const glm::dvec3& to) {
  d.edit(std::string("move ") + handleKindName(h.kind), [&](Scene& s) {
    Json* j = entry(s, h);
    if (!j || !isHandle(*j, h.kind)) gone(s, h);
    (*j)[pointKey(h.kind)] = actions::vec3Json(to);
  });
}

void removeHandle(Document& d, const Handle& h) {
  {
    Scene probe = d.scene();
    const Json* j = entry(probe, h);
    if (!j || !isHandle(*j, h.kind)) gone(probe, h);
  }
  switch (h.kind) {
    case HandleKind::Control:
      actions::removeControl(d, h.index);
      break;
    case HandleKind::Brush:
      actions::removeBrush(d, h.index);
      break;
    case HandleKind::Vector:
      actions::removeStylingVector(d, h.index);
      break;
    case HandleKind::KeyFeather:
      actions::removeKeyFeather(d, h.tract, h.index);
      break;
    case HandleKind::Pinned:
      d.edit("remove pinned follicle", [&](Scene& s) {
        Json& list = s.tracts.at(h.tract).at("pinned");
        list.erase(list.begin() + long(h.index));
        if (list.empty()) s.tracts[h.tract].erase("pinned");
      });
      break;
  }
}

std::vector<FollicleRef> follicleRefs(const Snapshot& s, const std::vector<int>& feathers,
                                      const std::vector<int>& follicles) {
  std::vector<FollicleRef> out;
  auto add = [&](int f) {
    if (f < 0 || size_t(f) >= s.follicleId.size() || size_t(f) >= s.follicleTract.size()) return;
    const FollicleRef r{s.follicleTract[size_t(f)], s.follicleId[size_t(f)]};
    if (std::find(out.begin(), out.end(), r) == out.end()) out.push_back(r);
  };
  for (int i : feathers)
    if (i >= 0 && size_t(i) < s.featherFollicle.size()) add(int(s.featherFollicle[size_t(i)]));
  for (int f : follicles) add(f);
  return out;
}

size_t removeHandles(Document& d, const std::vector<Handle>& hs, const std::vector<FollicleRef>& follicles) {
  // The handles that still exist, removed from the back of each list so earlier indices stay valid.
  std::vector<Handle> live;
  // The follicles not yet removed, of tracts the scene has (an empty list is the one whole-mesh tract).
  std::vector<FollicleRef> fresh;
  {
    Scene probe = d.scene();
    for (const Handle& h : hs) {
      const Json* j = entry(probe, h);
      if (j && isHandle(*j, h.kind) && std::find(live.begin(), live.end(), h) == live.end()) live.push_back(h);
    }
    const size_t tracts = std::max<size_t>(probe.tracts.size(), 1);
    for (const FollicleRef& f : follicles) {
      if (f.tract >= tracts || std::find(fresh.begin(), fresh.end(), f) != fresh.end()) continue;
      bool listed = false;
      if (f.tract < probe.tracts.size() && probe.tracts[f.tract].contains("removed_follicles"))
        for (const Json& v : probe.tracts[f.tract]["removed_follicles"])
          listed = listed || (v.is_number_integer() && v.get<uint64_t>() == f.id);
      if (!listed) fresh.push_back(f);
    }
  }
  if (live.empty() && fresh.empty()) return 0;
  std::sort(live.begin(), live.end(), [](const Handle& a, const Handle& b) {
    if (a.kind != b.kind) return a.kind < b.kind;
    if (a.tract != b.tract) return a.tract < b.tract;
    return a.index > b.index;
  });
  const std::string label = !fresh.empty() && live.empty() ? "remove " + std::to_string(fresh.size()) + " feathers"
                            : fresh.empty()                ? "remove " + std::to_string(live.size()) + " handles"
                                                           : "remove " + std::to_string(live.size()) + " handles and " +
                                                  std::to_string(fresh.size()) + " feathers";
  d.edit(label, [&](Scene& s) {
    for (const Handle& h : live) {
      switch (h.kind) {
        case HandleKind::Control:
          s.controls.erase(s.controls.begin() + long(h.index));
          break;
        case HandleKind::Brush:
          s.packing["styling"].erase(s.packing["styling"].begin() + long(h.index));
          if (s.packing["styling"].empty()) s.packing.erase("styling");
          break;
        case HandleKind::Vector:
          s.directions["vectors"].erase(s.directions["vectors"].begin() + long(h.index));
          if (s.directions["vectors"].empty()) s.directions.erase("vectors");
          break;
        case HandleKind::KeyFeather:
        case HandleKind::Pinned: {
          const char* key = h.kind == HandleKind::KeyFeather ? "key_feathers" : "pinned";
          Json& list = s.tracts[h.tract][key];
          list.erase(list.begin() + long(h.index));
          if (list.empty()) s.tracts[h.tract].erase(key);
          break;
        }
      }
    }
    if (s.tracts.empty() && !fresh.empty()) s.tracts = Json::array({Json{{"name", "all"}}});
    for (const FollicleRef& f : fresh) s.tracts[f.tract]["removed_follicles"].push_back(f.id);
  });
  return live.size() + fresh.size();
}

}  // namespace pteryla::viewer
