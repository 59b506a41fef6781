#include "mbot_slam_navigation/core/inflation_layer.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

namespace mbot {
namespace core {

void InflationParams::validate() const {
  if (!(inscribed_radius >= 0.0)) throw std::invalid_argument("inscribed radius must be >= 0");
  if (!(inflation_radius >= 0.0)) throw std::invalid_argument("inflation_radius must be >= 0");
  if (!(cost_scaling_factor >= 0.0)) throw std::invalid_argument("cost_scaling_factor must be >= 0");
}

uint8_t inflatedCost(double d, const InflationParams& p) {
  if (d <= 0.0) return cost::kLethal;
  if (d <= p.inscribed_radius) return cost::kInscribed;
  if (d > p.inflation_radius + 1e-9) return cost::kFree;  // a cell exactly at the radius is inflated
  return static_cast<uint8_t>((cost::kInscribed - 1) * std::exp(-p.cost_scaling_factor * (d - p.inscribed_radius)));
}

namespace {
/// [m] The largest cell-centre distance of a whole cell that can touch a footprint of contact_radius.
double farthestContact(double resolution, double contact_radius) {
  const double reach = contact_radius / resolution;  // [cells]
  double farthest = 0.0;                             // [cells]
  for (int dx = 0; dx <= static_cast<int>(reach) + 1; ++dx) {
    for (int dy = 0; dy <= dx; ++dy) {
      const double gap = std::hypot(std::max(dx - 0.5, 0.0), std::max(dy - 0.5, 0.0));  // to the cell's square
      if (gap < reach) farthest = std::max(farthest, std::hypot(dx, dy));
    }
  }
  return farthest * resolution;
}
}  // namespace

uint8_t contactCost(const InflationParams& p, double resolution, double contact_radius, double clearance) {
  if (clearance > 0.0) return inflatedCost(farthestContact(resolution, contact_radius) + clearance, p);
  const uint8_t c = inflatedCost(farthestContact(resolution, contact_radius), p);
  return c == cost::kFree || c > cost::kInscribed ? cost::kInscribed : c;
}

CellWindow CellWindow::unite(const CellWindow& o) const {
  if (empty()) return o;
  if (o.empty()) return *this;
  return {std::min(x0, o.x0), std::min(y0, o.y0), std::max(x1, o.x1), std::max(y1, o.y1)};
}

CellWindow CellWindow::grown(int cells, int width, int height) const {
  if (empty()) return *this;
  return {std::max(0, x0 - cells), std::max(0, y0 - cells), std::min(width, x1 + cells), std::min(height, y1 + cells)};
}

namespace {

// Inflation of `src`'s lethal cells into `dst` over `win`, reading `src` over `win` grown by the
// radius. src and dst may be the same grid (inflate() goes window by window in place): outside the
// window only which cells are lethal is read, raising a cell never makes it lethal, and each
// window cell's own value is read just before it is written.
void inflateInto(const Costmap& src, Costmap& dst, const CellWindow& win, const InflationParams& params) {
  params.validate();
  if (win.empty()) return;
  const int w = src.width(), h = src.height();
  const double res = src.resolution();
  // Cells farther than r (in cells) never take a cost; `cap` marks "no lethal cell within r".
  const int r = static_cast<int>(std::floor(params.inflation_radius / res + 1e-9));
  const int cap = r + 1;
  if (cap > 65000) throw std::invalid_argument("inflation_radius is more than 65000 cells");
  const CellWindow read = win.grown(r, w, h);
  const int rw = read.x1 - read.x0;
  // The cost for every squared distance [cells^2] that can occur within the radius.
  std::vector<uint8_t> by_d2(static_cast<std::size_t>(r) * r + 1);
  for (std::size_t d2 = 0; d2 < by_d2.size(); ++d2) by_d2[d2] = inflatedCost(std::sqrt(double(d2)) * res, params);
  const uint8_t* in = src.costs().data();
  uint8_t* out = dst.costs().data();

  // Column pass: for each cell of `read`'s columns and `win`'s rows, the vertical distance to the
  // nearest lethal cell of its column within `read` (capped). Sweeps run row by row across all the
  // columns at once, which the compiler vectorises.
  const int rows = win.y1 - win.y0;
  std::vector<uint16_t> g(static_cast<std::size_t>(rows) * rw, static_cast<uint16_t>(cap));
  std::vector<uint16_t> run(rw, static_cast<uint16_t>(cap));
  // Downward sweep from the top of `read`: distance to the nearest lethal cell above (or here).
  for (int y = read.y0; y < win.y1; ++y) {
    const uint8_t* row = in + static_cast<std::size_t>(y) * w + read.x0;
    for (int i = 0; i < rw; ++i) {
      const uint16_t up = static_cast<uint16_t>(std::min<int>(run[i] + 1, cap));
      run[i] = row[i] == cost::kLethal ? 0 : up;
    }
    if (y >= win.y0) std::copy(run.begin(), run.end(), g.begin() + static_cast<std::size_t>(y - win.y0) * rw);
  }
  // Upward sweep from the bottom of `read`: the nearer of that and the lethal cells below.
  std::fill(run.begin(), run.end(), static_cast<uint16_t>(cap));
  for (int y = read.y1 - 1; y >= win.y0; --y) {
    const uint8_t* row = in + static_cast<std::size_t>(y) * w + read.x0;
    for (int i = 0; i < rw; ++i) {
      const uint16_t down = static_cast<uint16_t>(std::min<int>(run[i] + 1, cap));
      run[i] = row[i] == cost::kLethal ? 0 : down;
    }
    if (y < win.y1) {
      uint16_t* gr = g.data() + static_cast<std::size_t>(y - win.y0) * rw;
      for (int i = 0; i < rw; ++i) gr[i] = std::min(gr[i], run[i]);
    }
  }

  // Row pass: d2(x) = min over |dx| <= r of dx^2 + g(x + dx)^2, only where some g is within r.
  const int cap2 = cap * cap;
  std::vector<uint32_t> g2(rw), d2(win.x1 - win.x0);
  std::vector<int> near;
  for (int y = win.y0; y < win.y1; ++y) {
    const uint16_t* gr = g.data() + static_cast<std::size_t>(y - win.y0) * rw;
    near.clear();
    for (int i = 0; i < rw; ++i) {
      g2[i] = static_cast<uint32_t>(gr[i]) * gr[i];
      if (gr[i] < cap) near.push_back(i);
    }
    if (near.empty()) continue;  // no lethal cell within the radius: nothing to raise
    std::fill(d2.begin(), d2.end(), static_cast<uint32_t>(cap2));
    const int off = win.x0 - read.x0;  // d2[j] is for read column off + j
    const int dw = win.x1 - win.x0;
    if (near.size() * (2 * r + 1) < static_cast<std::size_t>(rw) * 4) {
      // Few columns with an obstacle near: spread each over its neighbourhood.
      for (int i : near) {
        const int j0 = std::max(0, i - r - off), j1 = std::min(dw, i + r + 1 - off);
        for (int j = j0; j < j1; ++j) {
          const int dx = j + off - i;
          d2[j] = std::min<uint32_t>(d2[j], static_cast<uint32_t>(dx * dx) + g2[i]);
        }
      }
    } else {
      // Obstacles near most columns: one vectorisable sweep per offset.
      for (int dx = -r; dx <= r; ++dx) {
        const uint32_t dd = static_cast<uint32_t>(dx * dx);
        const int j0 = std::max(0, -dx - off), j1 = std::min(dw, rw - dx - off);
        const uint32_t* src2 = g2.data() + off + dx;
        for (int j = j0; j < j1; ++j) d2[j] = std::min<uint32_t>(d2[j], dd + src2[j]);
      }
    }
    const uint8_t* base_row = in + static_cast<std::size_t>(y) * w + win.x0;
    uint8_t* out_row = out + static_cast<std::size_t>(y) * w + win.x0;
    for (int j = 0; j < dw; ++j) {
      const uint8_t old = base_row[j];
      if (d2[j] > static_cast<uint32_t>(r) * r) {
        out_row[j] = old;
        continue;
      }
      const uint8_t c = by_d2[d2[j]];
      if (old == cost::kNoInformation) {
        out_row[j] = (params.inflate_unknown ? c > cost::kFree : c >= cost::kInscribed) ? c : old;
      } else {
        out_row[j] = std::max(old, c);
      }
    }
  }
}

}  // namespace

void inflate(Costmap& map, const InflationParams& params) {
  params.validate();
  // Only tiles within the radius of a tile holding a lethal cell can change: find those first (one
  // sequential read of the grid), then inflate tile row by tile row, each run of such tiles as one
  // window. In place is safe: the passes read only which cells are lethal, and raising a cell never
  // makes it lethal.
  constexpr int kTile = 32;
  const int w = map.width(), h = map.height();
  const int r = static_cast<int>(std::floor(params.inflation_radius / map.resolution() + 1e-9));
  const int tw = (w + kTile - 1) / kTile, th = (h + kTile - 1) / kTile;
  std::vector<uint8_t> lethal(static_cast<std::size_t>(tw) * th, 0);
  const uint8_t* c = map.costs().data();
  for (int y = 0; y < h; ++y) {
    const uint8_t* row = c + static_cast<std::size_t>(y) * w;
    uint8_t* flags = lethal.data() + static_cast<std::size_t>(y / kTile) * tw;
    // memchr (glibc's is vectorised) finds the next lethal cell; the rest of its tile is skipped.
    for (int x = 0; x < w;) {
      const void* hit = std::memchr(row + x, cost::kLethal, static_cast<std::size_t>(w - x));
      if (!hit) break;
      const int t = static_cast<int>(static_cast<const uint8_t*>(hit) - row) / kTile;
      flags[t] = 1;
      x = (t + 1) * kTile;
    }
  }
  const int reach = (r + kTile - 1) / kTile;  // tiles a lethal tile's inflation can reach
  std::vector<uint8_t> active(lethal.size(), 0);
  for (int ty = 0; ty < th; ++ty) {
    for (int tx = 0; tx < tw; ++tx) {
      if (!lethal[static_cast<std::size_t>(ty) * tw + tx]) continue;
      for (int y = std::max(0, ty - reach); y <= std::min(th - 1, ty + reach); ++y) {
        for (int x = std::max(0, tx - reach); x <= std::min(tw - 1, tx + reach); ++x) active[static_cast<std::size_t>(y) * tw + x] = 1;
      }
    }
  }
  for (int ty = 0; ty < th; ++ty) {
    const uint8_t* flags = active.data() + static_cast<std::size_t>(ty) * tw;
    for (int tx = 0; tx < tw;) {
      if (!flags[tx]) {
        ++tx;
        continue;
      }
      int end = tx;
      while (end < tw && flags[end]) ++end;
      inflateInto(map, map, CellWindow{tx * kTile, ty * kTile, std::min(w, end * kTile), std::min(h, (ty + 1) * kTile)}, params);
      tx = end;
    }
  }
}

void inflateWindow(const Costmap& base, Costmap& out, const CellWindow& window, const InflationParams& params) {
  if (base.width() != out.width() || base.height() != out.height()) {
    throw std::invalid_argument("inflateWindow: base and out must have the same size");
  }
  const CellWindow win = window.grown(0, base.width(), base.height());
  if (win.empty()) return;
  // Rows the pass skips keep base's values: copy them in first.
  for (int y = win.y0; y < win.y1; ++y) {
    const std::size_t i = static_cast<std::size_t>(y) * base.width();
    std::copy(base.costs().begin() + i + win.x0, base.costs().begin() + i + win.x1, out.costs().begin() + i + win.x0);
  }
  inflateInto(base, out, win, params);
}

void refineNearBoxes(const Costmap& base, Costmap& out, const CellWindow& window, const InflationParams& params,
                     double contact_radius) {
  const CellWindow win = window.grown(0, base.width(), base.height());
  if (win.empty() || !base.hasBoxes()) return;
  const int w = base.width();
  for (int y = win.y0; y < win.y1; ++y) {
    for (int x = win.x0; x < win.x1; ++x) out.setBox(static_cast<std::size_t>(y) * w + x, base.box(static_cast<std::size_t>(y) * w + x));
  }
  const double res = base.resolution();
  const double farthest = farthestContact(res, contact_radius);
  const double offset = farthest - contact_radius;  // [m] added to a distance to an obstacle's outline
  // Cells whose nearest whole-cell distance is at most `band` are refined: beyond it a box moves
  // the cost by less than the costs can matter to a footprint check or a plan through a gap.
  const double band = farthest + 1.5 * res;
  const int reach = static_cast<int>(std::ceil(band / res)) + 1;  // [cells] searched around a cell
  const uint8_t band_cost = inflatedCost(band, params);
  const uint8_t* in = base.costs().data();
  uint8_t* o = out.costs().data();
  // The lethal cells within reach of the window, row by row in x order, as world rectangles [m],
  // and how many of them have boxes in each rectangle of cells from the window's corner (a summed
  // area table: whether a cell has a box within reach is one lookup).
  struct Obstacle {
    int x;
    Eigen::Vector4d rect;
  };
  const CellWindow read = win.grown(reach, base.width(), base.height());
  const int rw = read.x1 - read.x0, rh = read.y1 - read.y0;
  std::vector<std::vector<Obstacle>> rows(static_cast<std::size_t>(rh));
  std::vector<int> boxed_sum(static_cast<std::size_t>(rw + 1) * (rh + 1), 0);
  const auto sum_at = [&](int x, int y) -> int& { return boxed_sum[static_cast<std::size_t>(y) * (rw + 1) + x]; };
  for (int y = read.y0; y < read.y1; ++y) {
    const uint8_t* row = in + static_cast<std::size_t>(y) * w;
    int in_row = 0;  // boxed lethal cells in this row left of x
    for (int x = read.x0; x < read.x1; ++x) {
      if (row[x] == cost::kLethal) {
        in_row += base.box(static_cast<std::size_t>(y) * w + x) != cell_box::kNoBox;
        rows[y - read.y0].push_back({x, base.obstacleBounds({x, y}, cell_box::kMargin)});
      }
      sum_at(x - read.x0 + 1, y - read.y0 + 1) = sum_at(x - read.x0 + 1, y - read.y0) + in_row;
    }
  }
  // An obstacle's rectangle lies within its cell grown by kMargin: a row (column) dy cells from a
  // cell's row is at least (|dy| - 1/2) cells less the margin from the cell's centre. Rows are
  // searched outwards from the cell's own, each only as far as the nearest obstacle found so far
  // allows (`keep`, below), so the obstacles that are measured are those that can matter.
  const double slack = 1e-6;  // [m] against rounding in the bounds
  const double inv_res = 1.0 / res;
  const auto gap = [&](int cells) { return std::max(0.0, (cells - 0.5) * res - cell_box::kMargin); };
  const double spread = res / 3.0 * std::sqrt(2.0);  // [m] from a cell's centre to its farthest sample point
  std::vector<std::pair<double, const Eigen::Vector4d*>> near;  // (squared centre distance [m^2], rectangle)
  for (int y = win.y0; y < win.y1; ++y) {
    for (int x = win.x0; x < win.x1; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      const uint8_t now = o[i];
      if (now == cost::kLethal || now < band_cost || now == cost::kNoInformation || now == cost::kFree) continue;
      // Only whole cells within reach: inflateWindow's cost stands.
      const int sx0 = std::max(read.x0, x - reach) - read.x0, sx1 = std::min(read.x1 - 1, x + reach) - read.x0 + 1;
      const int sy0 = std::max(read.y0, y - reach) - read.y0, sy1 = std::min(read.y1 - 1, y + reach) - read.y0 + 1;
      if (sum_at(sx1, sy1) - sum_at(sx0, sy1) - sum_at(sx1, sy0) + sum_at(sx0, sy0) == 0) continue;
      const Eigen::Vector2d centre = base.cellCenter({x, y});
      near.clear();
      // Squared distances [m^2] from the centre: to the nearest obstacle, and beyond which an
      // obstacle cannot be the nearest to any sample point.
      double nearest2 = std::numeric_limits<double>::infinity(), keep2 = nearest2;
      double keep = nearest2;  // [m]
      for (int k = 0; k <= 2 * reach; ++k) {
        const int dy = (k + 1) / 2 * (k % 2 ? 1 : -1);  // 0, 1, -1, 2, -2, ...
        const double gy = gap(std::abs(dy));
        if (gy > keep + slack) break;
        const int cy = y + dy;
        if (cy < read.y0 || cy >= read.y1) continue;
        const std::vector<Obstacle>& row = rows[cy - read.y0];
        if (row.empty()) continue;
        int dx_max = reach;
        if (!std::isinf(keep)) {
          const double gx = std::sqrt(std::max(0.0, (keep + slack) * (keep + slack) - gy * gy));  // [m]
          dx_max = std::min(reach, static_cast<int>((gx + cell_box::kMargin) * inv_res + 0.5));  // gx >= 0: truncation floors
        }
        auto it = std::lower_bound(row.begin(), row.end(), x - dx_max, [](const Obstacle& a, int v) { return a.x < v; });
        for (; it != row.end() && it->x <= x + dx_max; ++it) {
          const double d2 = cell_box::squaredDistance(it->rect, centre.x(), centre.y());
          if (d2 < nearest2) {
            nearest2 = d2;
            keep = std::sqrt(nearest2) + 2.0 * spread;
            keep2 = keep * keep;
          }
          if (d2 <= keep2) near.emplace_back(d2, &it->rect);
        }
      }
      // The clearance of the best of 3 x 3 points in the cell: a plan through a gap that is open
      // only within a centimetre or two of its middle must not depend on where the cell centres
      // fall (the local planner's footprint check is made at the robot's true pose). Only the
      // obstacles that can be nearest to one of the points are measured from each. A rectangle's
      // x and y distances to the points' x and y, squared, sum to the squared distances
      // (cell_box::squaredDistance, 6 differences instead of 18).
      double ax[3], ay[3];
      for (int k = 0; k < 3; ++k) {
        ax[k] = centre.x() + (k - 1) * (res / 3.0);
        ay[k] = centre.y() + (k - 1) * (res / 3.0);
      }
      double d2[9];
      std::fill(d2, d2 + 9, std::numeric_limits<double>::infinity());
      for (const auto& [centre_d2, r] : near) {
        if (centre_d2 > keep2) continue;  // found before the nearest: too far after all
        const Eigen::Vector4d& rect = *r;
        double ex[3], ey[3];
        for (int k = 0; k < 3; ++k) {
          ex[k] = std::max(std::max(rect[0] - ax[k], ax[k] - rect[2]), 0.0);
          ey[k] = std::max(std::max(rect[1] - ay[k], ay[k] - rect[3]), 0.0);
          ex[k] *= ex[k];
          ey[k] *= ey[k];
        }
        for (int j = 0; j < 3; ++j) {
          for (int k = 0; k < 3; ++k) d2[3 * j + k] = std::min(d2[3 * j + k], ex[k] + ey[j]);
        }
      }
      const double best = *std::max_element(d2, d2 + 9);
      const uint8_t c = inflatedCost(std::max(std::sqrt(best) + offset, 1e-6), params);
      if (in[i] == cost::kNoInformation) {
        o[i] = (params.inflate_unknown ? c > cost::kFree : c >= cost::kInscribed) ? c : in[i];
      } else {
        o[i] = std::max(in[i], c);
      }
    }
  }
}

}  // namespace core
}  // namespace mbot
