// pteryla-viewer: groom a bird and scrub its moult interactively (docs/viewer.md).
#include <CLI/CLI.hpp>

#include <cstdio>
#include <regex>

#include "app.hpp"
#include "pteryla/core/memory.hpp"
#include "script.hpp"

int main(int argc, char** argv) {
  pteryla::keepFreedMemoryInProcess();
  pteryla::viewer::ViewerOptions o;
  CLI::App cli{"pteryla-viewer: GLFW + Dear ImGui viewer over the pteryla pipeline (docs/viewer.md)"};
  std::string size;
  double lod = 0;
  bool noVsync = false, scriptHelp = false;
  cli.add_option("scene", o.scene, "Scene file (.json) or bare mesh (.obj/.ply/.off/.stl) to open");
  cli.add_option("--script", o.script, "Run a scripted session (see --script-help)");
  cli.add_flag("--script-help", scriptHelp, "List the script commands");
  cli.add_option("--screenshot", o.screenshot, "Capture the 3D view to this image once evaluated, then quit");
  cli.add_option("--frames", o.frames, "With --screenshot: draw at least this many frames first")
      ->check(CLI::Range(1, 1000000));
  cli.add_option("--benchmark-orbit", o.benchmarkOrbit,
                 "Orbit the camera once in N frames after the evaluation, print the frame rate as JSON, quit")
      ->check(CLI::Range(1, 1000000));
  cli.add_option("--size", size, "Window size WxH (default 1280x800)");
  cli.add_option("--lod", lod, "Level of detail in (0,1] (default: the scene's render.lod)")
      ->check(CLI::Range(1e-3, 1.0));
  cli.add_flag("--no-vsync", noVsync, "Do not wait for the display's refresh");
  cli.add_option("--autosave-seconds", o.autosaveSeconds,
                 "Write unsaved changes to a recovery file every N seconds (default 60, 0 = off; docs/viewer.md)")
      ->check(CLI::Range(0.0, 1e9));
  cli.add_option("--quit-after", o.quitAfter,
                 "Interactive run that quits after S seconds and prints the frames drawn and skipped as JSON "
                 "(checks that an idle viewer draws nothing)")
      ->check(CLI::Range(0.0, 1e9));
  cli.add_flag("--recover", o.recover,
               "Restore the autosaved unsaved work of SCENE (or, without SCENE, the newest) without asking");
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return cli.exit(e) == 0 ? 0 : 2;
  }
  if (scriptHelp) {
    std::fputs(pteryla::viewer::scriptHelp(), stdout);
    return 0;
  }
  if (!size.empty()) {
    std::smatch m;
    if (!std::regex_match(size, m, std::regex(R"((\d{2,5})x(\d{2,5}))"))) {
      std::fprintf(stderr, "pteryla-viewer: --size: expected WxH, e.g. 1280x800, got '%s'\n", size.c_str());
      return 2;
    }
    o.width = std::stoi(m[1]);
    o.height = std::stoi(m[2]);
  }
  if (lod > 0) o.lod = lod;
  o.vsync = !noVsync;
  return pteryla::viewer::runViewer(o);
}
