// The one translation unit that compiles tinygltf's implementation (Debian's libtinygltf-dev ships the
// header; compiling it here keeps it under our sanitizers). Image decoding and encoding are off: pteryla
// hands tinygltf image bytes in buffer views and never asks it to load files (the TINYGLTF_NO_* macros
// are set for the whole target in CMakeLists.txt: the class layout depends on them).
#define TINYGLTF_IMPLEMENTATION
#include <tiny_gltf.h>
