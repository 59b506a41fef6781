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
  HitCell() : visits(0), clears(0) {}
  float acc_x = 0.0f;   ///< sum of hit points' offsets from the cell centre [m]
  float acc_y = 0.0f;
  uint32_t hits = 0;
  uint32_t visits : 28;  ///< beams that ended in or passed through the cell
  /// Beams that passed clear through the cell since its last hit (see SlamGrid::kClearRange),
  /// saturating at 15. Four bits beside `visits` keep the cell at 16 bytes: every particle's map
  /// is made of these.
  uint32_t clears : 4;
  /// hits / visits, or -1 when never visited.
  double occupancy() const { return visits ? static_cast<double>(hits) / visits : -1.0; }
};
static_assert(sizeof(HitCell) == 16, "a HitCell is 16 bytes: the particles' maps are made of them");

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
  /// The cells of patch (px, py), row-major (kPatchSize per row), or nullptr when the patch lies
  /// outside the grid or was never written (all its cells are empty): the scan matcher reads a
  /// beam's whole window from one patch through it.
  const HitCell* patchCells(int px, int py) const {
    if (px < 0 || py < 0 || px >= patches_x_ || py >= patches_y_) return nullptr;
    const Patch* p = patches_[static_cast<std::size_t>(py) * patches_x_ + px].get();
    return p ? p->cells : nullptr;
  }
  /// Mean hit point of a cell [m, world]; its centre when it has no hits.
  Eigen::Vector2d hitMean(const Cell& c) const;

  /// Grows (whole patches) so that the box [min, max] (world, m) lies inside.
  void growToInclude(const Eigen::Vector2d& min_m, const Eigen::Vector2d& max_m);
  /// One beam from `from` to `to` (world, m): cells before the end are visited; the end cell is
  /// visited and, if `hit`, gains a hit at `to` (and its `clears` restart from 0). A cell within
  /// kClearRange of `from` and at least kClearBeyond before `to` was passed clear through, and
  /// gains a clear.
  void registerBeam(const Eigen::Vector2d& from, const Eigen::Vector2d& to, bool hit);

  /// Someone who stood still in the robot's view (a person in a door while the robot turned in
  /// its recoveries) gains as many hits as scans were taken, and gmapping's ratio keeps the cell
  /// occupied until three times as many beams have passed through it: the planner, which plans on
  /// this map, kept a door shut for minutes after they left. So a cell that kClearsToFree beams
  /// have passed clear through since its last hit shows free, whatever its ratio.
  ///
  /// Walls must not be worn away by this. A beam passes through a wall's cells only where it
  /// grazes the wall, and then only within res / sin(angle) of where it ends on it; a cell at most
  /// kClearRange from the laser, which stands at least h from any wall, is grazed at
  /// sin(angle) >= h / kClearRange. Counting only cells at least kClearBeyond before the beam's end
  /// therefore never counts a wall cell while h > res * kClearRange / kClearBeyond: 0.1 m at
  /// 0.05 m cells (the laser is inside the robot's footprint), 0.2 m at 0.1 m cells.
  static constexpr double kClearRange = 2.0;   ///< [m] from the laser
  static constexpr double kClearBeyond = 1.0;  ///< [m] before the beam's end
  static constexpr unsigned kClearsToFree = 4;
  /// Whether the map shows `c` occupied: hits / visits > occ_thresh (gmapping), and fewer than
  /// kClearsToFree clears since its last hit.
  static bool occupied(const HitCell& c, double occ_thresh) {
    return c.visits && c.hits > occ_thresh * c.visits && c.clears < kClearsToFree;
  }

  /// gmapping's map: a visited cell that is occupied() shows 100, any other visited cell 0.
  OccupancyImage toOccupancy(double occ_thresh) const;
  /// From now on, records which patches are written (off by default: the particles' grids,
  /// copied at every resampling, carry no record). updateOccupancy needs it.
  void trackWrites();
  /// Brings `image`, this grid's picture at `occ_thresh` as an earlier call left it (or empty),
  /// up to date, re-reading only the patches written since that call: a SLAM node publishes its
  /// map every few seconds and a scan writes a few patches of thousands. The whole picture is
  /// read again when it is empty, has another resolution or extent than the written part of the
  /// grid (a patch written outside it, the grid grown), or when writes were not tracked.
  /// The result equals toOccupancy(occ_thresh) as long as occ_thresh is the same in every call.
  void updateOccupancy(double occ_thresh, OccupancyImage& image);
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
  /// The written patches' box [px0, px1] x [py0, py1] (px1 < 0 when nothing is written).
  void writtenBox(int& px0, int& py0, int& px1, int& py1) const;
  /// Writes patch (px, py)'s cells into `img`, whose cell (0, 0) is patch (px0, py0)'s first.
  void drawPatch(int px, int py, int px0, int py0, double occ_thresh, OccupancyImage& img) const;
  static const HitCell empty_cell_;

  double resolution_;
  Eigen::Vector2d origin_;
  int patches_x_, patches_y_;
  std::vector<std::shared_ptr<Patch>> patches_;  // row-major, nullptr = never written
  // trackWrites: 1 for each patch written since the last updateOccupancy (as patches_); empty
  // when not tracking. all_written_: since then the grid grew, or tracking began.
  std::vector<uint8_t> written_;
  bool tracking_ = false, all_written_ = true;
};

}  // namespace core
}  // namespace mbot
