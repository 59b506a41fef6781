#include "mbot_slam_navigation/core/pose_graph.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include "mbot_slam_navigation/core/pose2d.h"

namespace mbot {
namespace core {

namespace {
Eigen::Matrix2d rotation(double yaw) {
  Eigen::Matrix2d r;
  r << std::cos(yaw), -std::sin(yaw), std::sin(yaw), std::cos(yaw);
  return r;
}

double edgeCost(const PoseGraphEdge& e, double s, double c) {
  if (!e.robust) return s;
  const double c2 = c * c;
  return c2 * std::log1p(s / c2);
}

double totalCost(const std::vector<Eigen::Vector3d>& poses, const std::vector<PoseGraphEdge>& edges, double c) {
  double cost = 0.0;
  for (const auto& e : edges) {
    const Eigen::Vector3d err = edgeError(poses[e.from], poses[e.to], e.measurement);
    cost += edgeCost(e, err.dot(e.information * err), c);
  }
  return cost;
}
}  // namespace

Eigen::Vector3d edgeError(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& z) {
  return relativePose(z, relativePose(a, b));
}

double robustWeight(const PoseGraphEdge& edge, double squared_error, double cauchy_scale) {
  if (!edge.robust) return 1.0;
  return 1.0 / (1.0 + squared_error / (cauchy_scale * cauchy_scale));
}

namespace {
PoseGraphSummary solve(std::vector<Eigen::Vector3d>& poses, const std::vector<PoseGraphEdge>& edges,
                       const PoseGraphOptions& options) {
  const int n = static_cast<int>(poses.size());
  PoseGraphSummary summary;
  summary.initial_cost = summary.final_cost = totalCost(poses, edges, options.cauchy_scale);
  if (n < 2 || edges.empty()) {
    summary.converged = true;
    return summary;
  }
  double lambda = 1e-6;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
  bool analyzed = false;
  std::vector<Eigen::Triplet<double>> triplets;
  for (int it = 0; it < options.max_iterations; ++it) {
    triplets.clear();
    triplets.reserve(edges.size() * 36 + 3 * n);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(3 * n);
    for (const auto& e : edges) {
      const Eigen::Vector3d& xi = poses[e.from];
      const Eigen::Vector3d& xj = poses[e.to];
      const Eigen::Vector3d err = edgeError(xi, xj, e.measurement);
      const double w = robustWeight(e, err.dot(e.information * err), options.cauchy_scale);
      // Jacobians of e = (Rz^T (Ri^T (tj - ti) - tz), thj - thi - thz) (the tutorial's eq. 30-31).
      const Eigen::Matrix2d RzT = rotation(e.measurement.z()).transpose();
      const Eigen::Matrix2d RiT = rotation(xi.z()).transpose();
      Eigen::Matrix2d dRiT;
      dRiT << -std::sin(xi.z()), std::cos(xi.z()), -std::cos(xi.z()), -std::sin(xi.z());
      const Eigen::Vector2d dt = xj.head<2>() - xi.head<2>();
      Eigen::Matrix3d A = Eigen::Matrix3d::Zero(), B = Eigen::Matrix3d::Zero();
      A.topLeftCorner<2, 2>() = -RzT * RiT;
      A.topRightCorner<2, 1>() = RzT * dRiT * dt;
      A(2, 2) = -1.0;
      B.topLeftCorner<2, 2>() = RzT * RiT;
      B(2, 2) = 1.0;
      const Eigen::Matrix3d O = w * e.information;
      const Eigen::Matrix3d Hii = A.transpose() * O * A, Hij = A.transpose() * O * B, Hjj = B.transpose() * O * B;
      b.segment<3>(3 * e.from) += A.transpose() * O * err;
      b.segment<3>(3 * e.to) += B.transpose() * O * err;
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
          triplets.emplace_back(3 * e.from + r, 3 * e.from + c, Hii(r, c));
          triplets.emplace_back(3 * e.from + r, 3 * e.to + c, Hij(r, c));
          triplets.emplace_back(3 * e.to + r, 3 * e.from + c, Hij(c, r));
          triplets.emplace_back(3 * e.to + r, 3 * e.to + c, Hjj(r, c));
        }
      }
    }
    for (int k = 0; k < 3 * n; ++k) triplets.emplace_back(k, k, k < 3 ? 1e12 : lambda);  // node 0 fixed
    Eigen::SparseMatrix<double> H(3 * n, 3 * n);
    H.setFromTriplets(triplets.begin(), triplets.end());
    if (!analyzed) {
      solver.analyzePattern(H);
      analyzed = true;
    }
    solver.factorize(H);
    if (solver.info() != Eigen::Success) {
      lambda *= 100.0;
      continue;
    }
    const Eigen::VectorXd dx = solver.solve(-b);
    std::vector<Eigen::Vector3d> trial = poses;
    for (int k = 1; k < n; ++k) {
      trial[k] += dx.segment<3>(3 * k);
      trial[k].z() = normalizeAngle(trial[k].z());
    }
    const double cost = totalCost(trial, edges, options.cauchy_scale);
    summary.iterations = it + 1;
    if (cost <= summary.final_cost * (1.0 + 1e-12)) {
      poses = std::move(trial);
      summary.final_cost = cost;
      lambda = std::max(1e-9, lambda * 0.1);
      if (dx.lpNorm<Eigen::Infinity>() < options.tolerance) {
        summary.converged = true;
        break;
      }
    } else {
      lambda *= 10.0;  // a step that made things worse: damp harder and try again
    }
  }
  return summary;
}

}  // namespace

PoseGraphSummary optimizePoseGraph(std::vector<Eigen::Vector3d>& poses, const std::vector<PoseGraphEdge>& edges,
                                   const PoseGraphOptions& options) {
  const int n = static_cast<int>(poses.size());
  for (const auto& e : edges) {
    if (e.from < 0 || e.to < 0 || e.from >= n || e.to >= n || e.from == e.to) {
      throw std::invalid_argument("pose graph: edge " + std::to_string(e.from) + " -> " + std::to_string(e.to) +
                                  " does not join two of the " + std::to_string(n) + " nodes");
    }
  }
  if (!options.graduated) return solve(poses, edges, options);
  const double initial_cost = totalCost(poses, edges, options.cauchy_scale);
  PoseGraphOptions wide = options;
  wide.cauchy_scale *= 10.0;
  const PoseGraphSummary first = solve(poses, edges, wide);
  PoseGraphSummary second = solve(poses, edges, options);
  second.iterations += first.iterations;
  second.initial_cost = initial_cost;
  return second;
}

}  // namespace core
}  // namespace mbot
