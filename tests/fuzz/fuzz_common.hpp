#pragma once
// Shared by the fuzz targets (tests/fuzz, issue #21 part 7): the readers under test take a path, so each
// input is written to a file in a per-process temporary directory, with the extension the reader needs.
// Targets catch pteryla::Error only (the documented answer to bad input); anything else that escapes
// (InternalError from PTERYLA_CHECK, std::bad_alloc, nlohmann exceptions, ...) aborts and is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <unistd.h>

namespace pteryla::fuzz {

inline std::filesystem::path& tempDirStorage() {
  static std::filesystem::path dir;
  return dir;
}

// Created on first use, removed at normal exit (a crash leaves it for inspection).
inline const std::filesystem::path& tempDir() {
  std::filesystem::path& dir = tempDirStorage();
  if (dir.empty()) {
    std::error_code ec;
    std::filesystem::path base = std::filesystem::temp_directory_path(ec);
    if (ec) base = "/tmp";
    dir = base / ("pteryla-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove_all(tempDirStorage(), ignored);
    });
  }
  return dir;
}

// Writes the input to <tempDir>/<name> and returns the path.
inline std::string writeInput(const uint8_t* data, size_t size, const std::string& name) {
  const std::string path = (tempDir() / name).string();
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();  // the harness itself is broken: not a finding in the library
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  return path;
}

// tempDir()/<sub>/ with tempDir()/{feathers,meshes,textures} linked to the bundled data/ (when the
// build passes PTERYLA_DATA_DIR), so the seeds' relative paths ("../feathers/contour.json") resolve as
// they do from data/scenes/ and the fuzzer gets past the file checks into the section parsers.
inline std::string dataLinkedDir(const std::string& sub) {
  const std::filesystem::path d = tempDir() / sub;
  if (!std::filesystem::exists(d)) {
    std::filesystem::create_directories(d);
#ifdef PTERYLA_DATA_DIR
    for (const char* name : {"feathers", "meshes", "textures"}) {
      std::error_code ec;
      std::filesystem::create_directory_symlink(std::filesystem::path(PTERYLA_DATA_DIR) / name, tempDir() / name, ec);
    }
#endif
  }
  return d.string();
}

}  // namespace pteryla::fuzz
