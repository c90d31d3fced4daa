// Shared by the yo-yo tracker tests: the committed scenes/pa10_yoyo.xml (the
// PA10 in its ready pose, the red yo-yo under its tool, the side webcam),
// the yo-yo placed at a chosen depth below the hand, rendered at 640 x 480
// with vlab_render's fast profile; ground truth from MuJoCo. On the MuJoCo
// fixture: any undeclared MuJoCo warning fails the test.
#pragma once

#include <memory>
#include <string>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <Eigen/Geometry>

#include "mujoco_fixture.h"
#include "render/renderer.h"
#include "test_util.h"
#include "vision/vision_detector.h"

namespace vlab::testing {

class YoyoCameraScene : public vlab::test::MujocoTest {
 protected:
  void SetUp() override {
    m_ = LoadModel("scenes/pa10_yoyo.xml");
    d_ = MakeData(m_);
    camera_ = mj_name2id(m_, mjOBJ_CAMERA, "webcam");
    centre_ = mj_name2id(m_, mjOBJ_SITE, "yoyo_centre");
    drop_ = m_->jnt_qposadr[mj_name2id(m_, mjOBJ_JOINT, "yoyo_drop")];
    spin_ = m_->jnt_qposadr[mj_name2id(m_, mjOBJ_JOINT, "yoyo_spin")];
    ASSERT_GE(camera_, 0);
    ASSERT_GE(centre_, 0);
    mj_resetDataKeyframe(m_, d_, mj_name2id(m_, mjOBJ_KEY, "hanging"));
    mj_forward(m_, d_);
    render::Renderer::Options options;
    options.width = 640;
    options.height = 480;
    options.profile = render::Profile::kFast;
    options.log_renderer = false;
    renderer_ = render::Renderer::Create(m_, options);
    const render::Intrinsics k = render::CameraIntrinsics(m_, camera_, 640, 480);
    model_ = vision::CameraModel{640, 480, k.fx, k.fy, k.cx, k.cy, {}};
  }
  /// The yo-yo's centre `depth` (m) below the hand, turned `spin` (rad), the arm still.
  void PlaceYoyo(double depth, double spin) {
    d_->qpos[drop_] = depth;
    d_->qpos[spin_] = spin;
    mj_forward(m_, d_);
  }
  void Render() { renderer_->Render(d_, camera_, &rgb_); }
  cv::Mat Image() { return cv::Mat(rgb_.height, rgb_.width, CV_8UC3, rgb_.pixels.data()); }

  Eigen::Vector3d TrueCentre() const {
    return Eigen::Vector3d(d_->site_xpos[3 * centre_], d_->site_xpos[3 * centre_ + 1], d_->site_xpos[3 * centre_ + 2]);
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

  mjModel* m_ = nullptr;  // owned by the MuJoCo fixture
  mjData* d_ = nullptr;
  int camera_ = -1, centre_ = -1, drop_ = -1, spin_ = -1;
  std::unique_ptr<render::Renderer> renderer_;  // freed before the model and data
  render::RgbImage rgb_;
  vision::CameraModel model_;
};

}  // namespace vlab::testing
