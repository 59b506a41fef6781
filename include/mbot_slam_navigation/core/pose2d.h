// Planar poses as Eigen::Vector3d (x [m], y [m], yaw [rad]) and their algebra (SE(2)).
#pragma once

#include <Eigen/Core>

namespace mbot {
namespace core {

/// Wraps an angle to (-pi, pi].
double normalizeAngle(double a);
/// a ⊕ b: b expressed in a's frame, returned in a's parent frame.
Eigen::Vector3d composePose(const Eigen::Vector3d& a, const Eigen::Vector3d& b);
/// The inverse pose: composePose(a, inversePose(a)) == 0.
Eigen::Vector3d inversePose(const Eigen::Vector3d& a);
/// ⊖: the pose of `to` in the frame of `from` (inversePose(from) ⊕ to).
Eigen::Vector3d relativePose(const Eigen::Vector3d& from, const Eigen::Vector3d& to);
/// Moves a pose along a constant-velocity arc: travel ds [m] while turning dtheta [rad].
Eigen::Vector3d integrateArc(const Eigen::Vector3d& pose, double ds, double dtheta);

}  // namespace core
}  // namespace mbot
