// The free bodies welded to an arm: a gripper mounted by a weld (MuJoCo 2.2.2 cannot add a
// child body to an included body tree; mjcf/gripper/README.md, "Mounting"). When the lab
// sets an arm's initial joints, each such body goes to its weld's pose at those joints, so
// that the weld does not snap it into place over the first steps.
#pragma once

#include <vector>

#include <mujoco/mujoco.h>

namespace vlab::lab {

/// The active body welds (equality `weld` with body1 and body2) that join a body of an arm's
/// chain (the subtree of the body that carries its first joint) to a free body (one free
/// joint, a child of the world) outside it.
class ArmWelds {
 public:
  /// The welds of the arm whose joints are `joint_ids` (model joint ids, chain order).
  static ArmWelds Find(const mjModel& m, const std::vector<int>& joint_ids);
  bool empty() const { return welds_.empty(); }
  /// Puts every welded free body at the pose its weld asks for (MuJoCo's weld: the pose of
  /// body1 times relpose is that of body2, its anchor on body2 at relpose's position) and
  /// zeroes its velocity. Reads the arm's body poses from `d` (after mj_kinematics); writes
  /// only the free bodies' qpos and qvel.
  void Place(const mjModel& m, mjData& d) const;

 private:
  struct Weld {
    int eq = -1;         // the equality
    int free_body = -1;  // the free body that follows
    int arm_body = -1;   // the arm's body it is welded to
    bool free_is_body2 = true;
    int qpos_adr = 0, dof_adr = 0;
  };
  std::vector<Weld> welds_;
};

}  // namespace vlab::lab
