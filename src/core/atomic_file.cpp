#include "pteryla/core/atomic_file.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

#include "pteryla/core/error.hpp"

namespace pteryla {
namespace {

// Permissions a plain fopen() would give a new file (mkstemp creates 0600).
mode_t newFileMode() {
  static const mode_t mode = [] {
    const mode_t mask = ::umask(022);
    ::umask(mask);
    return static_cast<mode_t>(0666 & ~mask);
  }();
  return mode;
}

}  // namespace

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  std::vector<char> name(path_.begin(), path_.end());
  const std::string suffix = ".tmp-XXXXXX";
  name.insert(name.end(), suffix.begin(), suffix.end());
  name.push_back('\0');
  const int fd = ::mkstemp(name.data());
  if (fd < 0) fail("cannot create a file next to it", errno);
  temp_ = name.data();
  ::fchmod(fd, newFileMode());
  f_ = ::fdopen(fd, "wb");
  if (!f_) {
    const int err = errno;
    ::close(fd);
    fail("cannot open for writing", err);
  }
  std::setvbuf(f_, nullptr, _IOFBF, 1 << 20);
}

AtomicFile::~AtomicFile() {
  if (f_) std::fclose(f_);
  if (!committed_ && !temp_.empty()) ::unlink(temp_.c_str());
}

void AtomicFile::fail(const std::string& what, int err) {
  std::string msg = what;
  if (err) msg += std::string(": ") + std::strerror(err);
  if (f_) {
    std::fclose(f_);
    f_ = nullptr;
  }
  if (!temp_.empty()) ::unlink(temp_.c_str());
  temp_.clear();
  throw Error(msg + " (nothing written; any previous file is unchanged)", path_);
}

void AtomicFile::write(const void* data, size_t n) {
  PTERYLA_CHECK(f_, "AtomicFile::write after releaseStream or commit");
  if (n && std::fwrite(data, 1, n, f_) != n) fail("write failed", errno);
}

void AtomicFile::releaseStream() {
  if (!f_) return;
  errno = 0;
  const bool bad = std::fflush(f_) != 0 || std::ferror(f_);
  const int err = errno;
  const int rc = std::fclose(f_);
  f_ = nullptr;
  if (bad || rc != 0) fail("write failed", err ? err : errno);
}

void AtomicFile::commit() {
  PTERYLA_CHECK(!committed_ && !temp_.empty(), "AtomicFile::commit twice");
  releaseStream();
  if (std::rename(temp_.c_str(), path_.c_str()) != 0) fail("cannot replace the file", errno);
  committed_ = true;
}

void writeFileAtomic(const std::string& path, const void* data, size_t n) {
  AtomicFile f(path);
  f.write(data, n);
  f.commit();
}

}  // namespace pteryla
