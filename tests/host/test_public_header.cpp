// The installed host API header stands alone: it compiles first in a translation unit and pulls in none
// of the library's dependencies (what a consumer of the installed package sees, tests/install).
#include "pteryla/pteryla.hpp"

#if defined(GLM_VERSION) || defined(GLM_SETUP_INCLUDED)
#error "pteryla.hpp pulls in GLM"
#endif
#if defined(NLOHMANN_JSON_VERSION_MAJOR) || defined(INCLUDE_NLOHMANN_JSON_HPP_)
#error "pteryla.hpp pulls in nlohmann/json"
#endif
#if defined(TBB_VERSION_MAJOR) || defined(__TBB_tbb_H)
#error "pteryla.hpp pulls in TBB"
#endif
#if defined(CGAL_VERSION_NR) || defined(OM_VERSION) || defined(OPENMESH_VERSION_HH)
#error "pteryla.hpp pulls in CGAL or OpenMesh"
#endif
#if defined(__gl_h_) || defined(__gl_glcorearb_h_) || defined(GL_VERSION_1_0)
#error "pteryla.hpp pulls in OpenGL"
#endif

#include <gtest/gtest.h>

#include <type_traits>

namespace {

TEST(HostApi, PublicTypesArePlainValues) {
  static_assert(std::is_nothrow_move_constructible_v<pteryla::Session>);
  static_assert(!std::is_copy_constructible_v<pteryla::Session>);
  static_assert(std::is_base_of_v<std::runtime_error, pteryla::Error>);
  pteryla::CoatSetup setup;
  EXPECT_TRUE(setup.tracts.empty());
  EXPECT_EQ(setup.packing, pteryla::CoatSetup::Packing::Drape);
  EXPECT_EQ(setup.seed, 1u);
}

}  // namespace
