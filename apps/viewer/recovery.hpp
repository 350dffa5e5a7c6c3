#pragma once
// Autosave and recovery of unsaved work (docs/viewer.md, "Autosave and recovery").
//
// While the document has unsaved changes the viewer writes its scene every N seconds (default 60,
// --autosave-seconds, 0 = off) to a recovery file in the state directory: $XDG_STATE_HOME/pteryla/recovery
// (default ~/.local/state/pteryla/recovery), one file per scene file ("NAME-HASH.json", HASH of the
// scene's absolute path), "untitled.json" for a scene that has no file yet. The file holds the scene (with
// absolute paths), the time and level of detail, and the scene file it belongs to; it is written to a
// temporary file in the same directory and renamed, so a crash while writing leaves the previous one.
// The user's scene file is never written by autosave or by a restore.
//
// The next start with that scene file (or with no scene: the newest recovery file) offers to restore it;
// a restore reopens the scene file and applies the recovered scene as one edit (undo returns to the file
// as saved), and the document stays modified until it is saved. Saving or discarding removes the file.
// No GL, no ImGui: unit-tested in tests/viewer.
#include <cstdint>
#include <optional>
#include <string>

#include "document.hpp"

namespace pteryla::viewer {

// The directory recovery files live in (not created here).
std::string recoveryDir();
// The recovery file of a scene file ("" = an untitled scene).
std::string recoveryPath(const std::string& scenePath);

struct Recovery {
  std::string file;               // the recovery file
  std::string scenePath;          // the scene file the work belongs to ("" untitled)
  std::string savedAt;            // UTC, ISO 8601
  pipeline::Scene scene;          // the time included (scene.time)
  std::optional<double> viewLod;  // the viewer's preview level of detail (older files: none)
};

// Writes the document's scene to recoveryPath(doc.path()) (temporary file, then rename); returns the
// path. Throws pteryla::Error when it cannot be written.
std::string writeRecovery(const Document& doc);
// Reads a recovery file; throws pteryla::Error naming it when it is not one.
Recovery readRecovery(const std::string& file);
// The recovery file for `scenePath` when it exists; for "" the newest recovery file there is.
std::optional<std::string> findRecovery(const std::string& scenePath);
// Restores into `doc`: reopens the scene file when it exists (unless it is the document's own, unmodified)
// and applies the recovered scene as one edit; otherwise starts an untitled document from the recovered
// scene. The document is modified afterwards. Throws pteryla::Error (the document is unchanged then
// unless the scene file had to be opened).
void restoreRecovery(Document& doc, const Recovery& r);
// Removes a recovery file (no error when it is gone).
void removeRecovery(const std::string& file);

// Writes a recovery file once the document has had unsaved changes, newer than the last write, for
// `interval` seconds; removes the file it wrote once the document is saved (not modified) or is another
// file now. Times are seconds on any monotonic clock (tick's `now`).
class Autosaver {
 public:
  explicit Autosaver(double intervalSeconds = 60.0) : interval_(intervalSeconds) {}
  void setInterval(double seconds) { interval_ = seconds; }
  double interval() const { return interval_; }
  // Once per frame. Returns true when it wrote the recovery file. Throws pteryla::Error when writing
  // fails (it tries again after another interval).
  bool tick(const Document& doc, double now);
  // Writes now (the `autosave` script command); throws when the document has nothing unsaved.
  std::string saveNow(const Document& doc);
  // The recovery file the document now corresponds to (after a restore): removed on a save like one it wrote.
  void adopt(const std::string& file, const Document& doc);
  // The user discarded the changes: removes the file it wrote.
  void discard();
  // At exit: removes the file when the document has nothing unsaved (the work is in the scene file).
  void finish(const Document& doc);
  const std::string& written() const { return written_; }

 private:
  void forgetIfSaved(const Document& doc);
  double interval_;
  std::string written_;
  uint64_t writtenChange_ = 0;
  double pendingSince_ = -1.0;  // when unsaved changes newer than the last write were first seen
};

}  // namespace pteryla::viewer
