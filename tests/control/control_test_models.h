// Inline MJCF test models for the control tests (loaded with the MuJoCo fixture's
// LoadModelFromString, tests/mujoco_fixture.h), and the rotations they build poses with.
#pragma once

#include <Eigen/Geometry>

namespace vlab::control::testing {

inline constexpr double kPi = 3.14159265358979323846;

/// The rotation by `angle` (rad) about `axis` (any length but zero).
inline Eigen::Matrix3d Rot(double angle, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

// A free-floating box first (so the arm's qpos and dof addresses differ and a
// free joint exists for error tests), then a 7-DOF spatial arm with hinges
// alternating z / y, armature and limits (j7 unlimited), tip site "tool" offset
// and rotated so the tip orientation is generic.
inline constexpr char kArm7Xml[] = R"(
<mujoco model="arm7">
  <compiler angle="radian"/>
  <option timestep="0.001" gravity="0 0 -9.81"/>
  <default>
    <joint type="hinge" limited="true" range="-2.9 2.9" armature="0.02"/>
    <geom type="capsule" size="0.03" density="1000" contype="0" conaffinity="0"/>
  </default>
  <worldbody>
    <body name="box" pos="1 1 0.5">
      <freejoint name="box_free"/>
      <geom type="box" size="0.05 0.05 0.05"/>
      <site name="box_site"/>
    </body>
    <body name="base" pos="0 0 0.1">
      <geom type="cylinder" size="0.06 0.05"/>
      <body name="l1" pos="0 0 0.05">
        <joint name="j1" axis="0 0 1"/>
        <geom fromto="0 0 0 0 0 0.2"/>
        <body name="l2" pos="0 0 0.2">
          <joint name="j2" axis="0 1 0" range="-2.0 2.0"/>
          <geom fromto="0 0 0 0.02 0 0.3"/>
          <body name="l3" pos="0.02 0 0.3">
            <joint name="j3" axis="0 0 1"/>
            <geom fromto="0 0 0 0 0 0.2"/>
            <body name="l4" pos="0 0 0.2">
              <joint name="j4" axis="0 1 0" range="-2.5 2.5"/>
              <geom fromto="0 0 0 -0.02 0 0.25"/>
              <body name="l5" pos="-0.02 0 0.25">
                <joint name="j5" axis="0 0 1"/>
                <geom fromto="0 0 0 0 0 0.15"/>
                <body name="l6" pos="0 0 0.15">
                  <joint name="j6" axis="0 1 0" range="-2.0 2.0"/>
                  <geom fromto="0 0 0 0 0.01 0.1"/>
                  <body name="l7" pos="0 0.01 0.1">
                    <joint name="j7" axis="0 0 1" limited="false"/>
                    <geom type="box" size="0.04 0.02 0.01" pos="0.01 0 0.03"/>
                    <site name="tool" pos="0 0 0.08" euler="0.3 -0.2 0.5"/>
                  </body>
                </body>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
)";

}  // namespace vlab::control::testing
