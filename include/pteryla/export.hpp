#pragma once
// PTERYLA_API marks what libpteryla.so exports: the host API (pteryla.hpp) and the error types it throws.
// Everything else is built with hidden visibility when PTERYLA_SHARED is on (CMakeLists.txt), so the
// library's inner modules, and the third-party code linked into it, stay private to it. Static builds
// ignore visibility; the attribute is harmless there. Exceptions must be exported so that a host's
// catch (const pteryla::Error&) matches what the library throws.
#if defined(__GNUC__) || defined(__clang__)
#define PTERYLA_API __attribute__((visibility("default")))
#else
#define PTERYLA_API
#endif
