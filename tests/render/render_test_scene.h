// Shared by the renderer tests: the pixel-facts scene (tests/data/render_pixels.xml)
// on the MuJoCo fixture (any undeclared MuJoCo warning fails the test), and the
// pinhole projection of world points into a camera, written from the camera frame
// conventions (MuJoCo: looks along -z, +y up; OpenCV: along +z, +y down).
#pragma once

#include <cmath>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include "mujoco_fixture.h"
#include "render/renderer.h"

namespace vlab::testing {

/// tests/data/render_pixels.xml loaded, its data after mj_forward.
class RenderScene : public vlab::test::MujocoTest {
 protected:
  void SetUp() override {
    m_ = LoadModel("tests/data/render_pixels.xml");
    d_ = MakeData(m_);
    mj_forward(m_, d_);
  }

  int Id(mjtObj type, const char* name) const {
    const int id = mj_name2id(m_, type, name);
    EXPECT_GE(id, 0) << name;
    return id;
  }
  /// Moves a mocap body and recomputes the kinematics.
  void Place(const char* body, double x, double y, double z) {
    const int mocap = m_->body_mocapid[Id(mjOBJ_BODY, body)];
    d_->mocap_pos[3 * mocap] = x;
    d_->mocap_pos[3 * mocap + 1] = y;
    d_->mocap_pos[3 * mocap + 2] = z;
    mj_forward(m_, d_);
  }

  mjModel* m_ = nullptr;
  mjData* d_ = nullptr;
};

/// A world point in the OpenCV frame of camera `cam` (x right, y down, z forward), m.
inline void WorldToCamera(const mjData* d, int cam, const double p_W[3], double p_C[3]) {
  const double* pos = d->cam_xpos + 3 * cam;
  const double* R = d->cam_xmat + 9 * cam;  // columns: camera x, y (up), z (backward) in world
  const double v[3] = {p_W[0] - pos[0], p_W[1] - pos[1], p_W[2] - pos[2]};
  const double x = R[0] * v[0] + R[3] * v[1] + R[6] * v[2];
  const double y = R[1] * v[0] + R[4] * v[1] + R[7] * v[2];
  const double z = R[2] * v[0] + R[5] * v[1] + R[8] * v[2];
  p_C[0] = x;
  p_C[1] = -y;
  p_C[2] = -z;
}

/// Pixel (u, v) of a world point in camera `cam` rendered with intrinsics k.
inline void Project(const mjData* d, int cam, const render::Intrinsics& k, const double p_W[3], double* u, double* v) {
  double p[3];
  WorldToCamera(d, cam, p_W, p);
  *u = k.fx * p[0] / p[2] + k.cx;
  *v = k.fy * p[1] / p[2] + k.cy;
}

}  // namespace vlab::testing
