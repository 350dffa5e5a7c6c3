#pragma once
// Scripted viewer sessions (`--script F`): one panel action per line, run in order, each after the
// previous one's evaluation has finished, so a script is deterministic. '#' starts a comment; arguments
// are separated by blanks and may be "quoted". The commands are listed by scriptHelp() and
// docs/viewer.md. Commands that change the scene go through actions.hpp (the same code the panels
// run); view commands (screenshot, orbit, ...) are carried out by the app.
#include <iosfwd>
#include <string>
#include <vector>

#include "document.hpp"

namespace pteryla::viewer {

struct ScriptCommand {
  int line = 0;  // 1-based line in the script
  std::string verb;
  std::vector<std::string> args;
};

// Throws pteryla::Error(file, "line N") for an unterminated quote.
std::vector<ScriptCommand> parseScript(const std::string& text, const std::string& file);
std::vector<ScriptCommand> loadScript(const std::string& path);

// Verbs the app carries out (they need the window): screenshot, orbit, zoom, frame, frames, quit.
bool isViewCommand(const std::string& verb);

// Runs a scene command on the document. Returns false for a view command or an unknown verb
// (the caller reports unknown verbs). Throws pteryla::Error(file, "line N: ...") for bad arguments or
// failed edits. `out` receives command output (check metrics, echo).
bool runDocumentCommand(Document& doc, const ScriptCommand& c, const std::string& file, std::ostream& out);

// Parses numbers strictly (the whole token), throwing Error(file, "line N") naming the argument.
double scriptNumber(const ScriptCommand& c, size_t arg, const std::string& file);
// Argument count check: throws with the usage string.
void needArgs(const ScriptCommand& c, size_t min, size_t max, const std::string& usage, const std::string& file);

// One JSON line with the checker's metrics (as `pteryla check` prints them).
std::string metricsJson(const pipeline::QualityMetrics& m);

const char* scriptHelp();

}  // namespace pteryla::viewer
