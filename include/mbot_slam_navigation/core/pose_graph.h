// A sparse 2D pose graph and its least-squares solution.
//
// Nodes are poses (x [m], y [m], yaw [rad]) in the map frame. An edge i -> j says "node j seen
// from node i is at z", with an information matrix (inverse covariance, in the frame of i). The
// error of an edge is e = z^-1 * (x_i^-1 * x_j) as (dx, dy, dyaw) (Grisetti, Kummerle, Stachniss,
// Burgard, "A Tutorial on Graph-Based SLAM", 2010, section IV); optimize() minimizes the sum of
// rho(e^T Omega e) by Gauss-Newton with Levenberg damping, each step solved with Eigen's sparse
// LDL^T (SimplicialLDLT). Node 0 is held fixed (the gauge).
//
// Robust edges (loop closures) use the Cauchy loss rho(s) = c^2 log(1 + s / c^2) through
// iteratively reweighted least squares, so that a wrong closure pulls with a weight that falls as
// its error grows instead of bending the whole map; odometry/scan-matching edges are plain
// squares.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace mbot {
namespace core {

struct PoseGraphEdge {
  int from = 0, to = 0;
  Eigen::Vector3d measurement = Eigen::Vector3d::Zero();  ///< pose of `to` in the frame of `from`
  Eigen::Matrix3d information = Eigen::Matrix3d::Identity();
  bool robust = false;  ///< Cauchy loss (loop closures)
};

struct PoseGraphOptions {
  int max_iterations = 20;          ///< per stage
  double cauchy_scale = 3.0;        ///< c of the Cauchy loss, in units of sqrt(e^T Omega e)
  /// Solve first with 10 * cauchy_scale, then with cauchy_scale. The Cauchy loss is not convex:
  /// started from drifted poses, where even good closures have large errors, it would weigh them
  /// all down; the wide stage lets consistent closures pull the drift out first.
  bool graduated = true;
  double tolerance = 1e-6;          ///< stop when no pose moves more than this [m or rad]
};

struct PoseGraphSummary {
  int iterations = 0;
  double initial_cost = 0.0, final_cost = 0.0;  ///< sum of rho over edges
  bool converged = false;
};

/// e = z^-1 * (a^-1 * b) for one edge, angle wrapped.
Eigen::Vector3d edgeError(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& z);

/// The weight an edge gets in the last reweighting: 1 for plain edges, 1 / (1 + s / c^2) for
/// robust ones (s = e^T Omega e).
double robustWeight(const PoseGraphEdge& edge, double squared_error, double cauchy_scale);

/// Optimizes `poses` in place (both stages when `graduated`); edges refer to indices of `poses`.
/// Throws std::invalid_argument on an edge whose index is out of range.
PoseGraphSummary optimizePoseGraph(std::vector<Eigen::Vector3d>& poses, const std::vector<PoseGraphEdge>& edges,
                                   const PoseGraphOptions& options);

}  // namespace core
}  // namespace mbot
