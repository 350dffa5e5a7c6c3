#pragma once
// The Open and Save As dialogs' file browser, and the recent-files list (docs/viewer.md, "Files").
// Pure std::filesystem: no ImGui, no GL (unit-tested in tests/viewer/test_file_browser.cpp).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace pteryla::viewer {

struct BrowserEntry {
  std::string name;  // file or directory name; ".." for the parent
  bool directory = false;
  uintmax_t bytes = 0;  // files only
};

class FileBrowser {
 public:
  // `extensions`: the files listed, lower case with the dot (".json"); empty lists every file.
  explicit FileBrowser(std::vector<std::string> extensions = {});

  // Lists `dir` (made absolute and normal). When it cannot be read, the old listing stays and error()
  // says why; returns whether it could.
  bool setDirectory(const std::string& dir);
  const std::string& directory() const { return dir_; }
  // ".." first (unless at the root), then directories, then files; each sorted by name, case-insensitive.
  // Names starting with '.' are left out unless showHidden.
  const std::vector<BrowserEntry>& entries() const { return entries_; }
  void setShowHidden(bool on);
  bool showHidden() const { return showHidden_; }
  void up();
  // Entry i chosen (a double-click): a directory is entered (nullopt); a file gives its absolute path.
  std::optional<std::string> choose(size_t i);
  // What the user typed in the file-name field, resolved as a shell would: "~" and "~/..." from $HOME,
  // an absolute path as it is, anything else against directory(). A directory is entered (nullopt).
  // The text replaces the old name: it is never appended to it.
  std::optional<std::string> resolveTyped(const std::string& text);
  const std::string& error() const { return error_; }

 private:
  void list();
  std::vector<std::string> extensions_;
  std::string dir_, error_;
  bool showHidden_ = false;
  std::vector<BrowserEntry> entries_;
};

// Files opened or saved lately, most recent first, each once, at most `limit`. Kept as JSON in a state
// file, written atomically; a missing or unreadable file is an empty list, never an error.
class RecentFiles {
 public:
  explicit RecentFiles(std::string file, size_t limit = 10);
  // <XDG_STATE_HOME or ~/.local/state>/pteryla/recent.json (next to the recovery directory).
  static std::string defaultFile();
  void load();
  // Moves `path` (made absolute) to the front and saves. A failed save keeps the list in memory and
  // returns false.
  bool add(const std::string& path);
  const std::vector<std::string>& list() const { return paths_; }
  const std::string& file() const { return file_; }

 private:
  std::string file_;
  size_t limit_;
  std::vector<std::string> paths_;
};

}  // namespace pteryla::viewer
