#pragma once
// The viewer's dialogs and the work they protect: errors (a modal listing them; the viewer keeps running),
// opening and saving scenes (asking about unsaved changes, asking before replacing a file), the Open and
// Save As file browsers with recent files, and autosave with the offer to recover unsaved work after a
// crash (recovery.hpp).
//   dialogs.cpp        the modals, open/save requests, autosave and recovery
//   dialogs_files.cpp  the Open and Save As dialogs (a file browser, recent files, Enter confirms)
#include <optional>
#include <string>
#include <vector>

#include "document.hpp"
#include "file_browser.hpp"
#include "panels.hpp"
#include "recovery.hpp"
#include "viewport.hpp"

namespace pteryla::viewer {

class Dialogs {
 public:
  struct Options {
    bool scripted = false;          // errors also go to stderr; recent files and recovery are left alone
    bool recover = false;           // --recover: restore the recovery file without asking
    double autosaveSeconds = 60.0;  // recovery file interval (0 = off)
  };
  // Opening a scene forgets the previous one's view (viewport) and selections (view).
  Dialogs(Document& doc, ViewState& view, Viewport& viewport, const Options& options);

  // Draws the open dialogs (once per frame, inside the ImGui frame).
  void draw();
  // Adds an error to the error modal (and stderr when scripted).
  void showError(const std::string& message);
  const std::vector<std::string>& errors() const { return errors_; }
  bool wantsToShow() const { return !popupToOpen_.empty(); }  // a dialog opens on the next frame

  // Open: asks about unsaved changes first; openNow does not (script `load`, after the question).
  void requestOpen(const std::string& path);
  void openNow(const std::string& path);
  void showOpen(const std::string& path = "");  // the Open dialog, starting at path when given
  void requestSave();                           // Save As when the scene has no file
  void requestSaveAs(const std::string& path = "");
  // Quit with unsaved changes: asks (Save / Discard / Cancel); quitRequested() once the answer allows it.
  void confirmQuit();
  bool quitRequested() const { return quit_; }
  // Recent files (user actions only: scripts leave them alone).
  void remember(const std::string& path);
  RecentFiles& recent() { return recent_; }
  // The path the Open dialog starts at (set when a scene failed to open).
  void setOpenPath(const std::string& path) { openPath_ = path; }

  // Autosave and recovery: at start, the unsaved work of the scene given (or, with no scene, the newest)
  // is offered; tick writes the recovery file while there are unsaved changes; finish removes it once
  // the scene is saved (or was never changed).
  void offerRecovery();
  void autosaveTick();
  std::string autosaveNow();  // script `autosave`: the file written
  void finish();

 private:
  enum class Pending { None, Quit, Open };
  void restoreOffered();
  void afterSave();  // carries on with what the unsaved-changes dialog was asked to do
  void saveAsNow(const std::string& path);
  void openDialog();    // dialogs_files.cpp
  void saveAsDialog();  // dialogs_files.cpp

  Document& doc_;
  ViewState& view_;
  Viewport& viewport_;
  Options options_;
  bool quit_ = false;

  // Autosave: the recovery file written while the scene has unsaved changes, and the one offered at start.
  Autosaver autosave_;
  std::optional<Recovery> offered_;
  bool autosaveErrorShown_ = false;

  std::vector<std::string> errors_;
  std::string popupToOpen_;
  Pending pending_ = Pending::None;
  std::string pendingPath_;
  std::string openPath_, saveAsPath_;
  FileBrowser openBrowser_{{".json", ".obj", ".ply", ".off", ".stl"}}, saveBrowser_{{".json"}};
  std::string openName_, saveName_;  // the dialogs' file-name fields
  bool focusName_ = false;           // put the keyboard in the file-name field when a dialog opens
  RecentFiles recent_{RecentFiles::defaultFile()};
};

}  // namespace pteryla::viewer
