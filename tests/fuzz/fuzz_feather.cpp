// Fuzz target: the feather reader (feather::loadFeather: "pteryla_feather": 1 files, docs/feather-format.md).
// A feather that loads is written back with featherToJson (save -> load is documented as exact).
#include <cstddef>
#include <cstdint>

#include "fuzz_common.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/feather/io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = pteryla::fuzz::writeInput(data, size, "feather.json");
  try {
    const pteryla::feather::FeatherParams p = pteryla::feather::loadFeather(path);
    (void)pteryla::feather::featherToJson(p, true);
  } catch (const pteryla::Error&) {
    // bad input: expected
  }
  return 0;
}
