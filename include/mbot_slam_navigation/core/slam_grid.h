// The map each SLAM particle carries: a counting grid (visits, hits and the mean hit point per
// cell, as GMapping's PointAccumulator), stored as copy-on-write patches so that particles which
// descend from the same ancestor share every patch neither has written since.
//
// Geometry as OccupancyGrid: `origin` is the world corner [m] of cell (0, 0); the grid grows in
// whole patches when a scan reaches beyond it, keeping every cell's world position.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <unordered_set>
#include <vector>

#include <Eigen/Core>

#include "mbot_slam_navigation/core/cell.h"

namespace mbot {
namespace core {

struct HitCell {
  float acc_x = 0.0f;   ///< sum of hit points' offsets from the cell centre [m]
  float acc_y = 0.0f;
  uint32_t hits = 0;
  uint32_t visits = 0;  ///< beams that ended in or passed through the cell
  /// hits / visits, or -1 when never visited.
  double occupancy() const { return visits ? static_cast<double>(hits) / visits : -1.0; }
};

/// An occupancy picture of a SlamGrid, cropped to the part that was ever written.
struct OccupancyImage {
  int width = 0, height = 0;
  double resolution = 0.0;
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  ///< world corner [m] of cell (0, 0)
  std::vector<int8_t> data;  ///< row-major from the lowest y: -1 unknown, 0 free, 100 occupied
};

class SlamGrid {
 public:
  static constexpr int kPatchBits = 4;  ///< 16 x 16 cells per patch
  static constexpr int kPatchSize = 1 << kPatchBits;

  /// An empty grid covering [min, max] (world, m) at `resolution_m`; throws std::invalid_argument.
  SlamGrid(const Eigen::Vector2d& min_m, const Eigen::Vector2d& max_m, double resolution_m);

  double resolution() const { return resolution_; }
  const Eigen::Vector2d& origin() const { return origin_; }
  int width() const { return patches_x_ * kPatchSize; }
  int height() const { return patches_y_ * kPatchSize; }

  // Inline: these two are the scan matcher's inner loop.
  Cell worldToCell(const Eigen::Vector2d& p) const { return core::worldToCell(origin_, resolution_, p); }
  Eigen::Vector2d cellCenter(const Cell& c) const { return core::cellCenter(origin_, resolution_, c); }
  /// The cell (a shared empty cell outside the grid or in unwritten patches).
  const HitCell& cell(const Cell& c) const {
    if (c.x < 0 || c.y < 0) return empty_cell_;
    const int px = c.x >> kPatchBits, py = c.y >> kPatchBits;
    if (px >= patches_x_ || py >= patches_y_) return empty_cell_;
    const Patch* p = patches_[static_cast<std::size_t>(py) * patches_x_ + px].get();
    if (!p) return empty_cell_;
    return p->cells[((c.y & (kPatchSize - 1)) << kPatchBits) | (c.x & (kPatchSize - 1))];
  }
  /// Mean hit point of a cell [m, world]; its centre when it has no hits.
  Eigen::Vector2d hitMean(const Cell& c) const;

  /// Grows (whole patches) so that the box [min, max] (world, m) lies inside.
  void growToInclude(const Eigen::Vector2d& min_m, const Eigen::Vector2d& max_m);
  /// One beam from `from` to `to` (world, m): cells before the end are visited; the end cell is
  /// visited and, if `hit`, gains a hit at `to`.
  void registerBeam(const Eigen::Vector2d& from, const Eigen::Vector2d& to, bool hit);

  /// gmapping's map: a visited cell with hits / visits > occ_thresh is occupied, else free.
  OccupancyImage toOccupancy(double occ_thresh) const;
  /// Patches allocated by this grid alone (not shared with any other grid) and in all.
  int ownedPatches() const;
  int allocatedPatches() const;
  /// Adds the addresses of this grid's patches to `out` (to count distinct patches across grids).
  void collectPatches(std::unordered_set<const void*>& out) const;
  static constexpr std::size_t kPatchBytes = kPatchSize * kPatchSize * sizeof(HitCell);

 private:
  struct Patch {
    HitCell cells[kPatchSize * kPatchSize];
  };
  HitCell& writableCell(const Cell& c);
  static const HitCell empty_cell_;

  double resolution_;
  Eigen::Vector2d origin_;
  int patches_x_, patches_y_;
  std::vector<std::shared_ptr<Patch>> patches_;  // row-major, nullptr = never written
};

}  // namespace core
}  // namespace mbot
