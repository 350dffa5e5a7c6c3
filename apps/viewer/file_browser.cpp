#include "file_browser.hpp"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "pteryla/core/atomic_file.hpp"
#include "pteryla/core/json.hpp"
#include "recovery.hpp"

namespace fs = std::filesystem;

namespace pteryla::viewer {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

std::string normal(const fs::path& p) {
  std::error_code ec;
  fs::path a = fs::absolute(p, ec);
  if (ec) a = p;
  std::string s = a.lexically_normal().string();
  // "/a/b/" -> "/a/b" (but keep "/").
  while (s.size() > 1 && s.back() == '/') s.pop_back();
  return s;
}

}  // namespace

FileBrowser::FileBrowser(std::vector<std::string> extensions) : extensions_(std::move(extensions)) {
  for (auto& e : extensions_) e = lower(e);
  std::error_code ec;
  const fs::path cwd = fs::current_path(ec);
  setDirectory(ec ? "/" : cwd.string());
}

bool FileBrowser::setDirectory(const std::string& dir) {
  const std::string d = normal(dir.empty() ? "/" : dir);
  std::error_code ec;
  if (!fs::is_directory(d, ec)) {
    error_ = "not a directory: " + d;
    return false;
  }
  const std::string old = dir_;
  dir_ = d;
  list();
  if (!error_.empty() && !old.empty()) {
    const std::string why = error_;
    dir_ = old;
    list();
    error_ = why;
    return false;
  }
  return error_.empty();
}

void FileBrowser::setShowHidden(bool on) {
  if (on == showHidden_) return;
  showHidden_ = on;
  list();
}

void FileBrowser::list() {
  error_.clear();
  std::vector<BrowserEntry> dirs, files;
  std::error_code ec;
  fs::directory_iterator it(dir_, fs::directory_options::skip_permission_denied, ec);
  if (ec) {
    error_ = "cannot read " + dir_ + ": " + ec.message();
    entries_.clear();
    return;
  }
  for (fs::directory_iterator end; it != end; it.increment(ec)) {
    if (ec) break;
    const std::string name = it->path().filename().string();
    if (name.empty() || (!showHidden_ && name[0] == '.')) continue;
    std::error_code e2;
    if (it->is_directory(e2)) {
      dirs.push_back({name, true, 0});
    } else if (it->is_regular_file(e2)) {
      const std::string ext = lower(it->path().extension().string());
      if (!extensions_.empty() && std::find(extensions_.begin(), extensions_.end(), ext) == extensions_.end()) continue;
      std::error_code e3;
      const uintmax_t bytes = it->file_size(e3);
      files.push_back({name, false, e3 ? 0 : bytes});
    }
  }
  auto byName = [](const BrowserEntry& a, const BrowserEntry& b) {
    const std::string la = lower(a.name), lb = lower(b.name);
    return la != lb ? la < lb : a.name < b.name;
  };
  std::sort(dirs.begin(), dirs.end(), byName);
  std::sort(files.begin(), files.end(), byName);
  entries_.clear();
  if (fs::path(dir_).has_relative_path()) entries_.push_back({"..", true, 0});
  entries_.insert(entries_.end(), dirs.begin(), dirs.end());
  entries_.insert(entries_.end(), files.begin(), files.end());
}

void FileBrowser::up() {
  const fs::path p(dir_);
  if (p.has_relative_path()) setDirectory(p.parent_path().string());
}

std::optional<std::string> FileBrowser::choose(size_t i) {
  if (i >= entries_.size()) return std::nullopt;
  const BrowserEntry e = entries_[i];
  if (e.name == "..") {
    up();
    return std::nullopt;
  }
  const std::string path = normal(fs::path(dir_) / e.name);
  if (e.directory) {
    setDirectory(path);
    return std::nullopt;
  }
  return path;
}

std::optional<std::string> FileBrowser::resolveTyped(const std::string& textIn) {
  std::string text = textIn;
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front()))) text.erase(text.begin());
  if (text.empty()) {
    error_ = "no file name given";
    return std::nullopt;
  }
  fs::path p;
  if (text == "~" || text.rfind("~/", 0) == 0) {
    const char* home = std::getenv("HOME");
    p = fs::path(home && home[0] ? home : "/") / text.substr(std::min<size_t>(2, text.size()));
  } else if (text[0] == '/') {
    p = text;
  } else {
    p = fs::path(dir_) / text;
  }
  const std::string path = normal(p);
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    setDirectory(path);
    return std::nullopt;
  }
  error_.clear();
  return path;
}

RecentFiles::RecentFiles(std::string file, size_t limit) : file_(std::move(file)), limit_(std::max<size_t>(limit, 1)) {}

std::string RecentFiles::defaultFile() { return (fs::path(recoveryDir()).parent_path() / "recent.json").string(); }

void RecentFiles::load() {
  paths_.clear();
  std::ifstream in(file_, std::ios::binary);
  if (!in) return;
  std::stringstream ss;
  ss << in.rdbuf();
  const Json j = Json::parse(ss.str(), nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("recent") || !j["recent"].is_array()) return;
  for (const Json& p : j["recent"])
    if (p.is_string() && !p.get<std::string>().empty() && paths_.size() < limit_ &&
        std::find(paths_.begin(), paths_.end(), p.get<std::string>()) == paths_.end())
      paths_.push_back(p.get<std::string>());
}

bool RecentFiles::add(const std::string& path) {
  const std::string abs = normal(path);
  paths_.erase(std::remove(paths_.begin(), paths_.end(), abs), paths_.end());
  paths_.insert(paths_.begin(), abs);
  if (paths_.size() > limit_) paths_.resize(limit_);
  try {
    std::error_code ec;
    fs::create_directories(fs::path(file_).parent_path(), ec);
    writeFileAtomic(file_, Json{{"recent", paths_}}.dump(1) + "\n");
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace pteryla::viewer
