#pragma once
// Atomic output files. Every file pteryla writes (images, meshes, scenes, frames) goes to a temporary
// file next to the target ("<name>.tmp-XXXXXX") and is renamed over the target only once everything was
// written and closed without error. A failed write (full disk, I/O error, a crash half-way) therefore never
// leaves a truncated file and never destroys the previous one.
#include <cstddef>
#include <cstdio>
#include <string>

#include "pteryla/export.hpp"

namespace pteryla {

class PTERYLA_API AtomicFile {
 public:
  // Creates the temporary file; throws pteryla::Error naming `path` when the directory is not writable.
  explicit AtomicFile(std::string path);
  ~AtomicFile();  // removes the temporary file unless commit() succeeded
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  const std::string& path() const { return path_; }
  const std::string& tempPath() const { return temp_; }
  // Buffered stream on the temporary file (null after releaseStream()).
  std::FILE* stream() const { return f_; }
  // Appends bytes; throws Error naming the target when the write fails.
  void write(const void* data, size_t n);
  void write(const std::string& s) { write(s.data(), s.size()); }
  // Closes our stream so another library can write tempPath() itself; throws Error when closing fails.
  void releaseStream();
  // Flushes, closes and renames the temporary file over path(); throws Error (old file kept) on failure.
  void commit();

 private:
  [[noreturn]] void fail(const std::string& what, int err);
  std::string path_, temp_;
  std::FILE* f_ = nullptr;
  bool committed_ = false;
};

// Writes `n` bytes to `path` atomically (see AtomicFile).
PTERYLA_API void writeFileAtomic(const std::string& path, const void* data, size_t n);
inline void writeFileAtomic(const std::string& path, const std::string& s) {
  writeFileAtomic(path, s.data(), s.size());
}

}  // namespace pteryla
