#pragma once
// SHA-256 (FIPS 180-4), used for frame checksums: a rendered frame's sidecar records the digest of its
// PNG so a rerun or an assembly step can tell a complete frame from a missing, truncated or altered one.
// Small and dependency-free so pteryla_core needs no crypto library.
#include <cstddef>
#include <cstdint>
#include <string>

#include "pteryla/export.hpp"

namespace pteryla {

// Lower-case hex digest (64 characters) of `n` bytes.
PTERYLA_API std::string sha256Hex(const void* data, size_t n);
inline std::string sha256Hex(const std::string& bytes) { return sha256Hex(bytes.data(), bytes.size()); }
// Digest of a whole file; empty string when it cannot be read.
PTERYLA_API std::string sha256File(const std::string& path);

}  // namespace pteryla
