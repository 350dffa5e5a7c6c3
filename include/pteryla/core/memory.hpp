#pragma once
// Process-wide memory settings for the applications (the pteryla CLI and the viewer).

#include "pteryla/export.hpp"

namespace pteryla {

// Keeps freed blocks of up to 32 MiB in the process instead of returning them to the system on every free
// (glibc: mmap threshold 32 MiB, trim threshold 128 MiB). Every pack, mesh and frame allocates and frees
// buffers of a few MiB; handed back and mapped again they cost a page fault per 4 KiB page each time (about
// 13 us on the project's VMs), and glibc's own adaptive threshold only rises after a large block is freed
// through malloc. Measured on the bird (docs/packing.md): warm repacks 0.29 -> 0.24 s, timeline frames
// 0.40 -> 0.33 s at 640x360. Call once at start-up. Returns whether the settings took (false without glibc).
PTERYLA_API bool keepFreedMemoryInProcess();

}  // namespace pteryla
