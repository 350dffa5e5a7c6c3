#include "recovery.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <system_error>

#include "pteryla/core/error.hpp"
#include "pteryla/core/hash.hpp"
#include "pteryla/core/json.hpp"
#include "pteryla/core/paths.hpp"
#include "scene_edit.hpp"

namespace pteryla::viewer {

namespace fs = std::filesystem;

namespace {

constexpr int kFormat = 1;

std::string envDir(const char* name) {
  const char* v = std::getenv(name);
  return v && v[0] == '/' ? std::string(v) : std::string();
}

uint64_t fnv1a(const std::string& s) { return fnv1a64(s.data(), s.size()); }

std::string utcNow() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string absolute(const std::string& path) { return fs::absolute(path).lexically_normal().string(); }

}  // namespace

std::string recoveryDir() {
  std::string base = envDir("XDG_STATE_HOME");
  if (base.empty()) {
    const std::string home = envDir("HOME");
    base = home.empty() ? (fs::temp_directory_path() / ("pteryla-state-" + std::to_string(getuid()))).string()
                        : home + "/.local/state";
  }
  return (fs::path(base) / "pteryla" / "recovery").string();
}

std::string recoveryPath(const std::string& scenePath) {
  if (scenePath.empty()) return (fs::path(recoveryDir()) / "untitled.json").string();
  const std::string abs = absolute(scenePath);
  char hash[17];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(fnv1a(abs)));
  return (fs::path(recoveryDir()) / (fs::path(abs).stem().string() + "-" + hash + ".json")).string();
}

std::string writeRecovery(const Document& doc) {
  if (!doc.hasScene()) throw Error("no scene is open");
  const std::string path = recoveryPath(doc.path());
  pipeline::Scene s = doc.scene();
  s.time = doc.time();
  if (s.densityFactor) {
    // The painted density map goes next to the recovery file (NAME-HASH.density.json), whole first.
    s.densityMap = pipeline::densityMapPathFor(path);
    std::error_code dirEc;
    fs::create_directories(fs::path(path).parent_path(), dirEc);
    pipeline::writeDensityMap(s.densityMap, *s.densityFactor);
  }
  const Json j = {{"pteryla_recovery", kFormat},
                  {"scene_path", doc.path()},
                  {"saved_at", utcNow()},
                  {"view_lod", doc.lod()},
                  {"scene", sceneJson(s)}};
  std::error_code ec;
  fs::create_directories(fs::path(path).parent_path(), ec);
  if (ec) throw Error("cannot create the recovery directory: " + ec.message(), fs::path(path).parent_path().string());
  // Temporary file in the same directory, then rename: the recovery file is always a complete one.
  const std::string tmp = path + ".tmp" + std::to_string(getpid());
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    f << j.dump(1) << '\n';
    f.flush();
    if (!f) {
      fs::remove(tmp, ec);
      throw Error("cannot write the recovery file", tmp);
    }
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw Error("cannot write the recovery file: " + ec.message(), path);
  }
  return path;
}

Recovery readRecovery(const std::string& file) {
  const Json j = readJsonFile(file);
  if (!j.is_object() || j.value("pteryla_recovery", 0) != kFormat || !j.contains("scene") || !j["scene"].is_object() ||
      !j.value("scene_path", Json()).is_string())
    throw Error("not a pteryla recovery file", file);
  Recovery r;
  r.file = file;
  r.scenePath = j["scene_path"].get<std::string>();
  if (j.contains("view_lod") && j["view_lod"].is_number()) {
    const double f = j["view_lod"].get<double>();
    if (f > 0 && f <= 1) r.viewLod = f;
  }
  r.savedAt = j.value("saved_at", std::string());
  try {
    r.scene = pipeline::sceneFromJson(j["scene"], r.scenePath);
  } catch (const Error& e) {
    throw Error(std::string("recovered scene: ") + e.what(), file);
  }
  return r;
}

std::optional<std::string> findRecovery(const std::string& scenePath) {
  std::error_code ec;
  if (!scenePath.empty()) {
    const std::string p = recoveryPath(scenePath);
    if (fs::is_regular_file(p, ec)) return p;
    return std::nullopt;
  }
  std::optional<std::string> best;
  fs::file_time_type bestTime{};
  for (fs::directory_iterator it(recoveryDir(), ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_regular_file(ec) || it->path().extension() != ".json") continue;
    if (it->path().stem().extension() == ".density") continue;  // a recovery file's painted density
    const auto t = fs::last_write_time(it->path(), ec);
    if (ec) continue;
    if (!best || t > bestTime) {
      best = it->path().string();
      bestTime = t;
    }
  }
  return best;
}

void restoreRecovery(Document& doc, const Recovery& r) {
  if (!r.scenePath.empty() && fileExists(r.scenePath)) {
    const bool open = doc.hasScene() && !doc.modified() && doc.path() == absolute(r.scenePath);
    if (!open) doc.open(r.scenePath);
    pipeline::Scene recovered = r.scene;
    recovered.file = doc.scene().file;
    doc.edit("restore unsaved work", [&](pipeline::Scene& s) { s = recovered; });
    doc.endGesture();
    doc.setTime(r.scene.time);
    doc.setLod(r.viewLod.value_or(r.scene.render.lod));
  } else {
    // The scene file is gone (or there never was one): the work comes back as an untitled scene.
    doc.reset(r.scene, "");
    doc.markModified();
  }
}

void removeRecovery(const std::string& file) {
  std::error_code ec;
  if (!file.empty()) fs::remove(file, ec);
  if (!file.empty()) fs::remove(pipeline::densityMapPathFor(file), ec);  // its painted density, if any
}

void Autosaver::forgetIfSaved(const Document& doc) {
  if (written_.empty()) return;
  if (!doc.hasScene() || !doc.modified() || written_ != recoveryPath(doc.path())) {
    removeRecovery(written_);
    written_.clear();
  }
}

bool Autosaver::tick(const Document& doc, double now) {
  forgetIfSaved(doc);
  if (interval_ <= 0 || !doc.hasScene() || !doc.modified() ||
      (!written_.empty() && writtenChange_ == doc.changeCount())) {
    pendingSince_ = -1.0;
    return false;
  }
  if (pendingSince_ < 0) pendingSince_ = now;
  if (now - pendingSince_ < interval_) return false;
  pendingSince_ = now;  // a failed write is retried after another interval
  saveNow(doc);
  return true;
}

std::string Autosaver::saveNow(const Document& doc) {
  forgetIfSaved(doc);
  if (!doc.hasScene() || !doc.modified()) throw Error("nothing to autosave: the scene has no unsaved changes");
  written_ = writeRecovery(doc);
  writtenChange_ = doc.changeCount();
  pendingSince_ = -1.0;
  return written_;
}

void Autosaver::adopt(const std::string& file, const Document& doc) {
  if (file == recoveryPath(doc.path())) {
    written_ = file;
    writtenChange_ = 0;  // written again at the next interval, under the same name
    return;
  }
  // The scene file has gone: the work is untitled now. Write it under that name before removing the old one.
  saveNow(doc);
  removeRecovery(file);
}

void Autosaver::discard() {
  removeRecovery(written_);
  written_.clear();
  pendingSince_ = -1.0;
}

void Autosaver::finish(const Document& doc) { forgetIfSaved(doc); }

}  // namespace pteryla::viewer
