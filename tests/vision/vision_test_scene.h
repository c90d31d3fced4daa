// Shared by the vision tests: a lettered cube (generated into a temporary
// folder) in front of a 640 x 480 webcam and its ground truth from MuJoCo, on
// the MuJoCo fixture (any undeclared MuJoCo warning fails the test).
#pragma once

#include <cmath>
#include <string>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <Eigen/Geometry>

#include "mujoco_fixture.h"
#include "test_util.h"
#include "vision/vision_cubes.h"
#include "vision/vision_scene.h"

namespace vlab::testing {

/// One cube of the default set (cube_A) on a free joint, a camera "cam" at
/// the origin looking along -z (MuJoCo's camera frame = the world frame), a
/// grey backdrop behind the cube, the cube scene's lights and webcam fovy.
class CubeCameraScene : public vlab::test::MujocoTest {
 protected:
  void SetUp() override {
    vision::WriteGeneratedFiles(dir_.path(), vision::CubeSetFiles(cubes_));
    const vision::CubeSceneConfig scene;
    const std::string xml =
        "<mujoco>\n"
        "  <compiler texturedir=\".\"/>\n"
        "  <visual><global offwidth=\"640\" offheight=\"480\"/></visual>\n"
        "  <include file=\"cubes_assets.xml\"/>\n"
        "  <worldbody>\n"
        "    <light pos=\"0.5 -1 1\" dir=\"-0.3 0.5 -1\" diffuse=\"0.7 0.7 0.7\"/>\n"
        "    <light pos=\"-1 1 1\" dir=\"0.5 -0.5 -1\" diffuse=\"0.3 0.3 0.3\"/>\n"
        "    <camera name=\"cam\" pos=\"0 0 0\" xyaxes=\"1 0 0 0 1 0\" fovy=\"" +
        vision::MjcfNumber(scene.webcam_fovy_deg) +
        "\"/>\n"
        "    <geom name=\"backdrop\" type=\"box\" size=\"3 3 0.01\" pos=\"0 0 -2\" rgba=\"0.45 0.42 0.40 1\"/>\n"
        "    <body name=\"cube_A\" pos=\"0 0 -0.4\">\n"
        "      <include file=\"cube_A.xml\"/>\n"
        "    </body>\n"
        "  </worldbody>\n"
        "</mujoco>\n";
    WriteFile(dir_ / "cube_camera.xml", xml);
    m_ = LoadModel(dir_ / "cube_camera.xml");
    d_ = MakeData(m_);
    camera_ = mj_name2id(m_, mjOBJ_CAMERA, "cam");
    mj_forward(m_, d_);
  }

  /// Puts the cube's centre at p (world = MuJoCo camera frame) with orientation q.
  void PlaceCube(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
    for (int i = 0; i < 3; ++i) d_->qpos[i] = p[i];
    d_->qpos[3] = q.w();
    d_->qpos[4] = q.x();
    d_->qpos[5] = q.y();
    d_->qpos[6] = q.z();
    mj_forward(m_, d_);
  }

  /// The OpenCV camera frame (x right, y down, z forward) in the world.
  Eigen::Isometry3d X_world_camera() const {
    Eigen::Matrix3d R;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) R(r, c) = d_->cam_xmat[9 * camera_ + 3 * r + c];
    }
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = R * Eigen::Vector3d(1, -1, -1).asDiagonal();
    X.translation() =
        Eigen::Vector3d(d_->cam_xpos[3 * camera_], d_->cam_xpos[3 * camera_ + 1], d_->cam_xpos[3 * camera_ + 2]);
    return X;
  }

  /// Ground truth: the marker frame of face f of the cube in the OpenCV camera frame.
  Eigen::Isometry3d X_camera_marker(int face) const {
    const int body = mj_name2id(m_, mjOBJ_BODY, "cube_A");
    Eigen::Isometry3d X_world_cube = Eigen::Isometry3d::Identity();
    const mjtNum* q = d_->xquat + 4 * body;
    X_world_cube.linear() = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).toRotationMatrix();
    X_world_cube.translation() = Eigen::Vector3d(d_->xpos[3 * body], d_->xpos[3 * body + 1], d_->xpos[3 * body + 2]);
    return X_world_camera().inverse() * X_world_cube * vision::CubeMarkerFrame(cubes_, face);
  }

  TempDir dir_;
  vision::CubeSetConfig cubes_;  // the default set: the committed mjcf/cubes
  mjModel* m_ = nullptr;         // owned by the MuJoCo fixture
  mjData* d_ = nullptr;
  int camera_ = -1;
};

}  // namespace vlab::testing
