#include "mbot_slam_navigation/core/slam_grid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "mbot_slam_navigation/core/bresenham.h"

namespace mbot {
namespace core {
const HitCell SlamGrid::empty_cell_{};

SlamGrid::SlamGrid(const Eigen::Vector2d& min_m, const Eigen::Vector2d& max_m, double resolution_m)
    : resolution_(resolution_m) {
  if (!(resolution_m > 0.0)) throw std::invalid_argument("SlamGrid: delta (resolution) must be positive");
  if (!(max_m.x() > min_m.x() && max_m.y() > min_m.y())) {
    throw std::invalid_argument("SlamGrid: xmax/ymax must exceed xmin/ymin");
  }
  const double patch_m = kPatchSize * resolution_;
  origin_ = min_m;
  patches_x_ = std::max(1, static_cast<int>(std::ceil((max_m.x() - min_m.x()) / patch_m)));
  patches_y_ = std::max(1, static_cast<int>(std::ceil((max_m.y() - min_m.y()) / patch_m)));
  patches_.assign(static_cast<std::size_t>(patches_x_) * patches_y_, nullptr);
}

Eigen::Vector2d SlamGrid::hitMean(const Cell& c) const {
  const HitCell& h = cell(c);
  Eigen::Vector2d centre = cellCenter(c);
  if (h.hits == 0) return centre;
  return centre + Eigen::Vector2d(h.acc_x, h.acc_y) / static_cast<double>(h.hits);
}

HitCell& SlamGrid::writableCell(const Cell& c) {
  std::shared_ptr<Patch>& p = patches_[static_cast<std::size_t>(c.y >> kPatchBits) * patches_x_ + (c.x >> kPatchBits)];
  if (tracking_) written_[static_cast<std::size_t>(c.y >> kPatchBits) * patches_x_ + (c.x >> kPatchBits)] = 1;
  if (!p) {
    p = std::make_shared<Patch>();
  } else if (p.use_count() > 1) {
    p = std::make_shared<Patch>(*p);  // copy on write: the other owners keep the old patch
  }
  return p->cells[((c.y & (kPatchSize - 1)) << kPatchBits) | (c.x & (kPatchSize - 1))];
}

void SlamGrid::growToInclude(const Eigen::Vector2d& min_m, const Eigen::Vector2d& max_m) {
  const double patch_m = kPatchSize * resolution_;
  const int add_left = std::max(0, static_cast<int>(std::ceil((origin_.x() - min_m.x()) / patch_m)));
  const int add_bottom = std::max(0, static_cast<int>(std::ceil((origin_.y() - min_m.y()) / patch_m)));
  const int add_right =
      std::max(0, static_cast<int>(std::ceil((max_m.x() - (origin_.x() + patches_x_ * patch_m)) / patch_m)));
  const int add_top =
      std::max(0, static_cast<int>(std::ceil((max_m.y() - (origin_.y() + patches_y_ * patch_m)) / patch_m)));
  if (add_left + add_bottom + add_right + add_top == 0) return;
  const int nx = patches_x_ + add_left + add_right, ny = patches_y_ + add_bottom + add_top;
  std::vector<std::shared_ptr<Patch>> grown(static_cast<std::size_t>(nx) * ny);
  for (int y = 0; y < patches_y_; ++y) {
    for (int x = 0; x < patches_x_; ++x) {
      grown[static_cast<std::size_t>(y + add_bottom) * nx + x + add_left] =
          std::move(patches_[static_cast<std::size_t>(y) * patches_x_ + x]);
    }
  }
  patches_ = std::move(grown);
  if (tracking_) {
    written_.assign(patches_.size(), 0);
    all_written_ = true;  // the picture's patch coordinates moved
  }
  patches_x_ = nx;
  patches_y_ = ny;
  origin_ -= Eigen::Vector2d(add_left, add_bottom) * patch_m;
}

void SlamGrid::registerBeam(const Eigen::Vector2d& from, const Eigen::Vector2d& to, bool hit) {
  const Cell start = worldToCell(from), end = worldToCell(to);
  const int w = width(), h = height();
  // In squared cells, so that the hot loop compares integers.
  const double range_cells = kClearRange / resolution_, beyond_cells = kClearBeyond / resolution_;
  const long range2 = static_cast<long>(range_cells * range_cells);
  const long beyond2 = static_cast<long>(std::ceil(beyond_cells * beyond_cells));
  walkLine(start, end, [&](const Cell& c) {
    if (c.x < 0 || c.y < 0 || c.x >= w || c.y >= h) return true;
    HitCell& cell = writableCell(c);
    if (cell.visits < (1u << 28) - 1) ++cell.visits;
    if (c == end) {
      if (hit) {
        const Eigen::Vector2d offset = to - cellCenter(c);
        cell.acc_x += static_cast<float>(offset.x());
        cell.acc_y += static_cast<float>(offset.y());
        ++cell.hits;
        cell.clears = 0;
      }
      return true;
    }
    const long fx = c.x - start.x, fy = c.y - start.y, ex = end.x - c.x, ey = end.y - c.y;
    if (cell.clears < 15 && fx * fx + fy * fy <= range2 && ex * ex + ey * ey >= beyond2) ++cell.clears;
    return true;
  });
}

void SlamGrid::writtenBox(int& px0, int& py0, int& px1, int& py1) const {
  px0 = patches_x_, py0 = patches_y_, px1 = -1, py1 = -1;
  for (int py = 0; py < patches_y_; ++py) {
    for (int px = 0; px < patches_x_; ++px) {
      if (!patches_[static_cast<std::size_t>(py) * patches_x_ + px]) continue;
      px0 = std::min(px0, px);
      py0 = std::min(py0, py);
      px1 = std::max(px1, px);
      py1 = std::max(py1, py);
    }
  }
}

void SlamGrid::drawPatch(int px, int py, int px0, int py0, double occ_thresh, OccupancyImage& img) const {
  const Patch* patch = patches_[static_cast<std::size_t>(py) * patches_x_ + px].get();
  for (int cy = 0; cy < kPatchSize; ++cy) {
    int8_t* row = &img.data[static_cast<std::size_t>((py - py0) * kPatchSize + cy) * img.width + (px - px0) * kPatchSize];
    if (!patch) {
      std::fill(row, row + kPatchSize, int8_t{-1});
      continue;
    }
    const HitCell* cells = &patch->cells[cy << kPatchBits];
    for (int cx = 0; cx < kPatchSize; ++cx) row[cx] = cells[cx].visits ? (occupied(cells[cx], occ_thresh) ? 100 : 0) : -1;
  }
}

OccupancyImage SlamGrid::toOccupancy(double occ_thresh) const {
  int px0, py0, px1, py1;
  writtenBox(px0, py0, px1, py1);
  OccupancyImage img;
  img.resolution = resolution_;
  if (px1 < 0) return img;
  img.width = (px1 - px0 + 1) * kPatchSize;
  img.height = (py1 - py0 + 1) * kPatchSize;
  img.origin = origin_ + Eigen::Vector2d(px0, py0) * kPatchSize * resolution_;
  img.data.assign(static_cast<std::size_t>(img.width) * img.height, -1);
  // Patch by patch: cells of absent patches stay unknown without being looked up one by one.
  for (int py = py0; py <= py1; ++py) {
    for (int px = px0; px <= px1; ++px) {
      if (patches_[static_cast<std::size_t>(py) * patches_x_ + px]) drawPatch(px, py, px0, py0, occ_thresh, img);
    }
  }
  return img;
}

void SlamGrid::trackWrites() {
  if (tracking_) return;
  tracking_ = true;
  written_.assign(patches_.size(), 0);
  all_written_ = true;
}

void SlamGrid::updateOccupancy(double occ_thresh, OccupancyImage& image) {
  const double patch_m = kPatchSize * resolution_;
  bool whole = !tracking_ || all_written_ || image.data.empty() || image.resolution != resolution_;
  int px0 = 0, py0 = 0, px1 = -1, py1 = -1;
  if (!whole) {
    // The picture's patch box, from its origin: patches never move while the grid does not grow.
    const Eigen::Vector2d at = (image.origin - origin_) / patch_m;
    px0 = static_cast<int>(std::lround(at.x()));
    py0 = static_cast<int>(std::lround(at.y()));
    px1 = px0 + image.width / kPatchSize - 1;
    py1 = py0 + image.height / kPatchSize - 1;
    for (std::size_t i = 0; i < written_.size() && !whole; ++i) {
      if (!written_[i]) continue;
      const int px = static_cast<int>(i % patches_x_), py = static_cast<int>(i / patches_x_);
      whole = px < px0 || px > px1 || py < py0 || py > py1;
    }
  }
  if (whole) {
    image = toOccupancy(occ_thresh);
  } else {
    for (std::size_t i = 0; i < written_.size(); ++i) {
      if (written_[i]) drawPatch(static_cast<int>(i % patches_x_), static_cast<int>(i / patches_x_), px0, py0, occ_thresh, image);
    }
  }
  if (tracking_) {
    std::fill(written_.begin(), written_.end(), 0);
    all_written_ = false;
  }
}

int SlamGrid::ownedPatches() const {
  int n = 0;
  for (const auto& p : patches_) n += p && p.use_count() == 1;
  return n;
}

void SlamGrid::collectPatches(std::unordered_set<const void*>& out) const {
  for (const auto& p : patches_) {
    if (p) out.insert(p.get());
  }
}

int SlamGrid::allocatedPatches() const {
  int n = 0;
  for (const auto& p : patches_) n += p != nullptr;
  return n;
}

}  // namespace core
}  // namespace mbot
