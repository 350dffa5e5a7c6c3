// Handles (handles.hpp): every control, brush sphere, styling vector, key feather at a point and pinned
// follicle is listed where it is; moving one edits only its point (one undo step); removing it removes
// that element; a handle that is gone is an error that changes nothing. No display.
#include <gtest/gtest.h>

#include "actions.hpp"
#include "document.hpp"
#include "fixtures.hpp"
#include "handles.hpp"
#include "pteryla/core/error.hpp"
#include "scene_edit.hpp"

using namespace pteryla;
using namespace pteryla::viewer;
using viewer_test::smallPatch;

TEST(Handles, ListMoveAndRemoveEveryKind) {
  Document d;
  d.reset(smallPatch(), "");  // one styling vector at the origin, two key feathers at points
  actions::addControl(d, {0.2, 0.05, 0.1}, 0.3);
  actions::addBrush(d, {-0.3, 0.05, 0.2}, 0.2, 30);
  d.edit("comb", [](pipeline::Scene& s) {  // a comb selection has no handle
    s.packing["styling"].push_back(Json::parse(R"({"select": "comb", "from": [0,0,0], "to": [1,0,0], "radius": 0.1,
                                                   "direction": [0, 0, 1]})"));
  });
  actions::addPinned(d, 0, {0.5, 0.05, -0.5});
  actions::setTractFeather(d, 0, "contour");  // the tract still says its feather once its key feathers are gone
  std::vector<Handle> hs = sceneHandles(d.scene());
  ASSERT_EQ(hs.size(), 6u);
  EXPECT_EQ(hs[0].kind, HandleKind::Control);
  EXPECT_EQ(hs[1].kind, HandleKind::Brush);
  EXPECT_EQ(hs[2].kind, HandleKind::Vector);
  EXPECT_EQ(hs[3].kind, HandleKind::KeyFeather);
  EXPECT_EQ(hs[5].kind, HandleKind::Pinned);
  EXPECT_EQ(hs[1].at, glm::vec3(-0.3f, 0.05f, 0.2f));
  EXPECT_NE(handleReadout(d.scene(), hs[0]).find("control 0 'control0'"), std::string::npos);
  EXPECT_NE(handleReadout(d.scene(), hs[3]).find("feather: contour"), std::string::npos);

  for (const Handle& h : hs) {
    SCOPED_TRACE(handleKindName(h.kind));
    d.endGesture();
    const Json before = sceneJson(d.scene());
    moveHandle(d, h, {0.7, 0.06, 0.7});
    const auto moved = findHandle(d.scene(), h);
    ASSERT_TRUE(moved);
    EXPECT_EQ(moved->at, glm::vec3(0.7f, 0.06f, 0.7f));
    // Only that point changed: putting it back gives the scene before.
    ASSERT_TRUE(d.undo());
    EXPECT_EQ(sceneJson(d.scene()), before);
  }
  // Remove, from the last (indices of earlier ones stay valid).
  for (size_t i = hs.size(); i-- > 0;) {
    d.endGesture();
    removeHandle(d, hs[i]);
    EXPECT_EQ(sceneHandles(d.scene()).size(), i);
  }
  EXPECT_TRUE(d.scene().controls.empty());
  EXPECT_EQ(d.scene().packing["styling"].size(), 1u) << "the comb stays";
  EXPECT_FALSE(d.scene().tracts[0].contains("pinned"));
  const Json after = sceneJson(d.scene());
  EXPECT_THROW(removeHandle(d, hs[0]), Error);
  EXPECT_THROW(moveHandle(d, hs[0], {0, 0, 0}), Error);
  EXPECT_EQ(sceneJson(d.scene()), after);
  ASSERT_TRUE(d.waitIdle()) << d.takeError().value_or("");
}

TEST(Handles, RemoveSeveralIsOneEditAndSkipsWhatIsGone) {
  Document d;
  d.reset(smallPatch(), "");  // one styling vector, two key feathers at points
  actions::addPinned(d, 0, {0.1, 0.05, 0.1});
  actions::addPinned(d, 0, {0.2, 0.05, 0.1});
  actions::addPinned(d, 0, {0.3, 0.05, 0.1});
  d.endGesture();
  const std::vector<Handle> all = sceneHandles(d.scene());
  ASSERT_EQ(all.size(), 6u);  // vector, 2 key feathers, 3 pinned
  // The first and last pinned follicles and the second key feather, plus a handle that does not exist.
  std::vector<Handle> pick = {all[3], all[5], all[2], Handle{HandleKind::Control, 7, 0, {}}};
  EXPECT_EQ(removeHandles(d, pick), 3u);
  const Json& t = d.scene().tracts[0];
  ASSERT_EQ(t["pinned"].size(), 1u);
  EXPECT_EQ(t["pinned"][0]["at"][0], 0.2);
  ASSERT_EQ(t["key_feathers"].size(), 1u);
  EXPECT_EQ(t["key_feathers"][0]["feather"], "contour");
  ASSERT_TRUE(d.undo());  // one step back restores all three
  EXPECT_EQ(sceneHandles(d.scene()).size(), 6u);
  EXPECT_EQ(removeHandles(d, {Handle{HandleKind::Brush, 0, 0, {}}}), 0u);  // nothing there: no edit
}

// Deleting feathers (Delete on a clicked or boxed feather): their follicles' ids go to their tracts'
// removed_follicles, with the boxed handles, as one edit; follicles already removed make no edit.
TEST(Handles, DeletingFeathersListsTheirFollicleIdsInOneEdit) {
  Document d;
  d.reset(smallPatch(), "");
  d.edit("two tracts", [](pipeline::Scene& s) {
    Json t = s.tracts[0];
    t["name"] = "second";
    t.erase("key_feathers");
    t["feather"] = "contour";
    s.tracts.push_back(t);
  });
  actions::addPinned(d, 0, {0.1, 0.05, 0.1});
  d.endGesture();
  Snapshot snap;  // three follicles (ids 40, 41 of tract 0; 90 of tract 1), feathers on 2, 0, 1
  snap.follicleId = {40, 41, 90};
  snap.follicleTract = {0, 0, 1};
  snap.featherFollicle = {2, 0, 1};
  // Feathers 0 and 1, follicle 0 again (once), an out-of-range feather and follicle (skipped).
  const std::vector<FollicleRef> refs = follicleRefs(snap, {0, 1, 7, -1}, {0, 3});
  ASSERT_EQ(refs.size(), 2u);
  EXPECT_EQ(refs[0], (FollicleRef{1, 90}));
  EXPECT_EQ(refs[1], (FollicleRef{0, 40}));

  const Json before = sceneJson(d.scene());
  const std::vector<Handle> pinned = {sceneHandles(d.scene()).back()};
  ASSERT_EQ(pinned[0].kind, HandleKind::Pinned);
  EXPECT_EQ(removeHandles(d, pinned, refs), 3u);
  EXPECT_EQ(d.undoLabel(), "remove 1 handles and 2 feathers");
  EXPECT_EQ(d.scene().tracts[0]["removed_follicles"], Json::array({40}));
  EXPECT_EQ(d.scene().tracts[1]["removed_follicles"], Json::array({90}));
  EXPECT_FALSE(d.scene().tracts[0].contains("pinned"));
  d.endGesture();
  // Again: both are listed already and the handle is gone, so nothing changes. A third follicle adds.
  EXPECT_EQ(removeHandles(d, pinned, refs), 0u);
  EXPECT_EQ(removeHandles(d, {}, {FollicleRef{0, 41}, FollicleRef{5, 1}}), 1u);  // tract 5 does not exist
  EXPECT_EQ(d.scene().tracts[0]["removed_follicles"], Json::array({40, 41}));
  ASSERT_TRUE(d.undo());
  ASSERT_TRUE(d.undo());  // one step back restores the pinned follicle and both feathers
  EXPECT_EQ(sceneJson(d.scene()), before);
  ASSERT_TRUE(d.waitIdle()) << d.takeError().value_or("");
}
