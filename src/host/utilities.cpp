// The host API's utilities (include/pteryla/pteryla.hpp includes their headers) live in the module
// archives. libpteryla.so takes an archive member only when something in it is referenced, and nothing in
// the library calls these: the table below references each, so their members are linked in and their
// PTERYLA_API symbols exported.
#include "pteryla/pteryla.hpp"

namespace pteryla {
namespace {

__attribute__((used)) void* const kHostUtilities[] = {
    reinterpret_cast<void*>(&keepFreedMemoryInProcess),
    reinterpret_cast<void*>(&render::diffImages),
    reinterpret_cast<void*>(&render::differenceImage),
    reinterpret_cast<void*>(static_cast<std::string (*)(const std::string&)>(&sha256File)),
    reinterpret_cast<void*>(static_cast<std::string (*)(const void*, size_t)>(&sha256Hex)),
};

}  // namespace
}  // namespace pteryla
