// pteryla_patterns: writes the standard synthesised feather textures (pattern.hpp) as PNGs.
//   pteryla_patterns --out data/textures [--seed 1]
#include <CLI/CLI.hpp>

#include <filesystem>
#include <iostream>

#include "pteryla/core/error.hpp"
#include "pteryla/render/pattern.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Write pteryla's synthesised feather colour patterns and barb alpha masks as PNG files"};
  std::string out = "textures";
  uint64_t seed = 1;
  app.add_option("--out", out, "output directory (created if missing)");
  app.add_option("--seed", seed, "pattern seed (the committed data/textures use 1)");
  CLI11_PARSE(app, argc, argv);
  try {
    std::filesystem::create_directories(out);
    for (const std::string& path : pteryla::render::writeStandardTextures(out, seed)) std::cout << path << "\n";
  } catch (const pteryla::Error& e) {
    std::cerr << "pteryla_patterns: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "pteryla_patterns: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
