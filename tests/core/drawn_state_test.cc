// CopyDrawnState (src/core/core_mujoco.h): a scene drawn from the copy is the
// scene drawn from the state it was taken from, with every visual flag on
// (contact points and forces, tendons, centres of mass, inertia boxes, joints,
// actuators, constraints), while the constraint matrices and the stack are left
// out; and the comparison can tell a state that misses a part of it.
#include <cstring>
#include <string>

#include <gtest/gtest.h>

#include "core/core_mujoco.h"

namespace vlab {
namespace {

// boxes falling on a plane (contacts, constraint forces), a tendon over a site,
// a mocap body, a light, a camera: every kind of array a drawing reads
constexpr const char* kSceneXml = R"(
<mujoco>
  <worldbody>
    <light pos="0 0 3" dir="0 0 -1"/>
    <camera name="side" pos="0 -2 1" xyaxes="1 0 0 0 0.5 1"/>
    <geom type="plane" size="2 2 0.1"/>
    <body name="a" pos="0 0 0.3"><freejoint/><geom type="box" size="0.1 0.1 0.1"/><site name="sa"/></body>
    <body name="b" pos="0.05 0.02 0.6" euler="10 20 30"><freejoint/><geom type="box" size="0.1 0.1 0.1"/><site name="sb"/></body>
    <body name="arm" pos="-0.6 0 0.5">
      <joint name="hinge" type="hinge" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
      <site name="tip" pos="0.3 0 0"/>
    </body>
    <body name="target" mocap="true" pos="0.5 0.5 0.5"><geom type="sphere" size="0.05" contype="0" conaffinity="0"/></body>
  </worldbody>
  <tendon><spatial name="t"><site site="tip"/><site site="sa"/></spatial></tendon>
  <actuator><motor joint="hinge" gear="1"/></actuator>
</mujoco>)";

mjvScene Draw(const mjModel* m, mjData* d) {
  mjvOption opt;
  mjv_defaultOption(&opt);
  for (int i = 0; i < mjNVISFLAG; ++i) opt.flags[i] = 1;
  mjvCamera cam;
  mjv_defaultCamera(&cam);
  cam.type = mjCAMERA_FIXED;
  cam.fixedcamid = 0;
  mjvScene scene;
  mjv_defaultScene(&scene);
  mjv_makeScene(m, &scene, 2000);
  mjv_updateScene(m, d, &opt, nullptr, &cam, mjCAT_ALL, &scene);
  return scene;
}

// the geoms, lights and camera of two drawn scenes are the same, field by field
::testing::AssertionResult SameScene(const mjvScene& a, const mjvScene& b) {
  if (a.ngeom != b.ngeom) return ::testing::AssertionFailure() << a.ngeom << " geoms vs " << b.ngeom;
  for (int i = 0; i < a.ngeom; ++i) {
    const mjvGeom& g = a.geoms[i];
    const mjvGeom& h = b.geoms[i];
    const bool same = g.type == h.type && g.dataid == h.dataid && g.objtype == h.objtype && g.objid == h.objid &&
                      g.category == h.category && std::memcmp(g.size, h.size, sizeof g.size) == 0 &&
                      std::memcmp(g.pos, h.pos, sizeof g.pos) == 0 && std::memcmp(g.mat, h.mat, sizeof g.mat) == 0 &&
                      std::memcmp(g.rgba, h.rgba, sizeof g.rgba) == 0 && std::strcmp(g.label, h.label) == 0;
    if (!same)
      return ::testing::AssertionFailure()
             << "geom " << i << " (type " << g.type << ", object " << g.objid << ") differs";
  }
  if (a.nlight != b.nlight) return ::testing::AssertionFailure() << a.nlight << " lights vs " << b.nlight;
  for (int i = 0; i < a.nlight; ++i) {
    if (std::memcmp(a.lights[i].pos, b.lights[i].pos, sizeof a.lights[i].pos) != 0 ||
        std::memcmp(a.lights[i].dir, b.lights[i].dir, sizeof a.lights[i].dir) != 0) {
      return ::testing::AssertionFailure() << "light " << i << " differs";
    }
  }
  for (int e = 0; e < 2; ++e) {
    if (std::memcmp(a.camera[e].pos, b.camera[e].pos, sizeof a.camera[e].pos) != 0 ||
        std::memcmp(a.camera[e].forward, b.camera[e].forward, sizeof a.camera[e].forward) != 0) {
      return ::testing::AssertionFailure() << "camera eye " << e << " differs";
    }
  }
  return ::testing::AssertionSuccess();
}

TEST(DrawnStateTest, TheCopyDrawsTheSameSceneWithoutTheConstraintMatrices) {
  ModelPtr m = LoadModelFromString("drawn_state_test", kSceneXml);
  DataPtr d = MakeData(m.get());
  d->ctrl[0] = 0.5;
  d->mocap_pos[0] = 0.4;
  for (int i = 0; i < 1000; ++i) mj_step(m.get(), d.get());  // the boxes rest on the plane and on each other
  ASSERT_GT(d->ncon, 4) << "the scene has contacts to draw";
  ASSERT_GT(d->nefc, 0);

  DataPtr copy = MakeData(m.get());
  // what the copy leaves out keeps its own values: mark it to see it untouched
  std::memset(copy->efc_J, 0x5a, sizeof(mjtNum) * m->njmax * m->nv);
  CopyDrawnState(m.get(), d.get(), copy.get());
  EXPECT_EQ(copy->time, d->time);
  EXPECT_EQ(copy->ncon, d->ncon);
  EXPECT_EQ(copy->nefc, d->nefc);
  EXPECT_EQ(copy->pstack, 0);
  EXPECT_EQ(std::memcmp(copy->efc_force, d->efc_force, sizeof(mjtNum) * d->nefc), 0);
  EXPECT_EQ(std::memcmp(copy->contact, d->contact, sizeof(mjContact) * d->ncon), 0);
  unsigned char mark;
  std::memcpy(&mark, copy->efc_J, 1);
  EXPECT_EQ(mark, 0x5a) << "the constraint Jacobian was copied";

  mjvScene drawn = Draw(m.get(), d.get());
  mjvScene from_copy = Draw(m.get(), copy.get());
  EXPECT_GT(drawn.ngeom, m->ngeom + d->ncon) << "contacts, tendons and frames were drawn";
  EXPECT_TRUE(SameScene(drawn, from_copy));

  // the comparison sees a copy whose contact forces differ (the forces drawn change)
  for (int i = 0; i < copy->nefc; ++i) copy->efc_force[i] *= 2;
  mjvScene doubled = Draw(m.get(), copy.get());
  EXPECT_FALSE(SameScene(drawn, doubled));
  mjv_freeScene(&drawn);
  mjv_freeScene(&from_copy);
  mjv_freeScene(&doubled);
}

}  // namespace
}  // namespace vlab
