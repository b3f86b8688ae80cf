// write_map_figure() of figures.h: a field as colour bands, contours, hatched
// masked cells, markers, arrows and a colour bar.
#include <fmt/format.h>
#include <plplot.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <opencv2/core.hpp>
#include <stdexcept>

#include "report/figure_frame.h"
#include "report/figures.h"

namespace bosfuse::report {

using namespace figure_frame;  // the frame every figure draws in (figure_frame.h)

namespace {

namespace fs = std::filesystem;

constexpr int kMaxDrawnCells = 250;  // per map side; finer grids are block-averaged for drawing
constexpr int kMaxContours = 60;
constexpr int kBands = 24;  // colour bands between the colour scale's ends

// A rectangle of grid nodes, rows r0..r1 and columns c0..c1 inclusive, every
// one of them measured.
struct MeasuredBlock {
  int r0, r1, c0, c1;
};

// The measured part of the grid as rectangles whose nodes are all measured:
// the runs of whole cells (four measured corners) along each row of cells,
// a run extended downwards while the next row has the same run. Colour bands
// and contours are computed inside these only, from measured values alone,
// so nothing is interpolated into or across a masked region and a contour
// neither enters the mask nor dives towards it at its edge.
std::vector<MeasuredBlock> measured_blocks(const cv::Mat& masked) {
  std::vector<MeasuredBlock> blocks;
  std::map<std::pair<int, int>, std::size_t> open;  // run (c0, c1) → block reaching the previous row of cells
  auto measured = [&](int r, int c) { return masked.at<std::uint8_t>(r, c) == 0; };
  for (int r = 0; r + 1 < masked.rows; ++r) {
    std::map<std::pair<int, int>, std::size_t> next;
    for (int c = 0; c + 1 < masked.cols;) {
      auto whole = [&](int cc) {
        return measured(r, cc) && measured(r, cc + 1) && measured(r + 1, cc) && measured(r + 1, cc + 1);
      };
      if (!whole(c)) {
        ++c;
        continue;
      }
      int end = c;
      while (end + 2 < masked.cols && whole(end + 1)) ++end;
      const std::pair run{c, end + 1};  // node columns
      if (const auto it = open.find(run); it != open.end()) {
        blocks[it->second].r1 = r + 1;
        next[run] = it->second;
      } else {
        blocks.push_back({r, r + 1, run.first, run.second});
        next[run] = blocks.size() - 1;
      }
      c = end + 1;
    }
    open = std::move(next);
  }
  return blocks;
}

// A measured node beside a not-measured one (or on a thin grid) lies on the
// edge of the bands drawn in measured_blocks(): it is drawn as its own cell in
// its own colour, so it shows without a value being invented beside it.
bool needs_own_cell(const cv::Mat& masked, int r, int c) {
  if (masked.at<std::uint8_t>(r, c)) return false;
  if (masked.rows < 2 || masked.cols < 2) return true;
  for (int dr = -1; dr <= 1; ++dr) {
    for (int dc = -1; dc <= 1; ++dc) {
      const int rr = r + dr, cc = c + dc;
      if (rr >= 0 && cc >= 0 && rr < masked.rows && cc < masked.cols && masked.at<std::uint8_t>(rr, cc)) return true;
    }
  }
  return false;
}

// World units per mm of the current viewport, along x and y.
std::array<double, 2> world_per_mm() {
  PLFLT sx0 = 0, sx1 = 0, sy0 = 0, sy1 = 0, vx0 = 0, vx1 = 0, vy0 = 0, vy1 = 0, wx0 = 0, wx1 = 0, wy0 = 0, wy1 = 0;
  plgspa(&sx0, &sx1, &sy0, &sy1);
  plgvpd(&vx0, &vx1, &vy0, &vy1);
  plgvpw(&wx0, &wx1, &wy0, &wy1);
  return {std::abs(wx1 - wx0) / ((vx1 - vx0) * (sx1 - sx0)), std::abs(wy1 - wy0) / ((vy1 - vy0) * (sy1 - sy0))};
}

// Thermocouple positions: a black dot ringed in white, its name in black on
// a white box beside it, so it reads on any colour of the map.
void draw_markers(const std::vector<MapMarker>& markers, double scale, std::array<double, 2> wx,
                  std::array<double, 2> wy) {
  plschr(0, 0.8);
  PLFLT default_mm = 0, height_mm = 0;
  plgchr(&default_mm, &height_mm);
  const auto [per_mm_x, per_mm_y] = world_per_mm();
  for (const auto& m : markers) {
    const PLFLT x = m.image_px.x * scale, y = m.image_px.y * scale;
    if (x < wx[0] || x > wx[1] || y < wy[0] || y > wy[1]) continue;
    plcol0(kBackground);
    plssym(0, 1.6);
    plpoin(1, &x, &y, 17);
    plcol0(kInk);
    plssym(0, 1.2);
    plpoin(1, &x, &y, 17);
    const std::string label = pl_text(m.name);
    const double left = x + 0.02 * (wx[1] - wx[0]);
    const double width = (0.72 * height_mm * static_cast<double>(codepoints(m.name)) + 1.5) * per_mm_x;
    const double half_height = 0.9 * height_mm * per_mm_y;
    const double pad = 0.75 * per_mm_x;
    const std::array<PLFLT, 4> bx{left - pad, left + width, left + width, left - pad};
    const std::array<PLFLT, 4> by{y - half_height, y - half_height, y + half_height, y + half_height};
    plcol0(kBackground);
    plfill(4, bx.data(), by.data());
    plcol0(kInk);
    plptex(left, y, 1, 0, 0, label.c_str());
  }
  plssym(0, 1);
  plschr(0, 1);
}

// The legend's one entry, in the figure's bottom right corner: the hatch
// pattern of the cells that hold no measurement.
void draw_mask_legend() {
  const PLINT opts[] = {PL_LEGEND_COLOR_BOX}, text_colours[] = {kInk}, box_colours[] = {kMaskHatch},
              box_patterns[] = {3}, unused_int[] = {0};
  const PLFLT box_scales[] = {1.2}, box_widths[] = {1.0}, unused_float[] = {0};
  const char* texts[] = {"hatched: masked or not measured (no value)"};
  const char* no_symbol[] = {""};
  PLFLT width = 0, height = 0;
  plschr(0, 0.8);
  pllegend(&width, &height, 0, PL_POSITION_RIGHT | PL_POSITION_BOTTOM | PL_POSITION_INSIDE | PL_POSITION_SUBPAGE, 0.01,
           0.01, 0.05, kBackground, kInk, 1, 0, 0, 1, opts, 0.5, 0.8, 1.5, 1.0, text_colours,
           texts, box_colours, box_patterns, box_scales, box_widths, unused_int, unused_int, unused_float, unused_int,
           unused_float, unused_int, no_symbol);
  plschr(0, 1);
}

struct GridTransform {
  double x0, y0, step, scale;  // world = (x0 + i·step)·scale
};

void grid_to_world(PLFLT i, PLFLT j, PLFLT* x, PLFLT* y, PLPointer data) {
  const auto* g = static_cast<const GridTransform*>(data);
  *x = (g->x0 + i * g->step) * g->scale;
  *y = (g->y0 + j * g->step) * g->scale;
}

// At most about 32 arrows a side, on every stride-th node of the grid:
// denser arrows are unreadable. PLplot scales them so the longest spans
// about one drawn cell.
void draw_arrows(const MapField& map, double scale) {
  if (map.u_px.size() != map.values.size() || map.v_px.size() != map.values.size()) {
    throw std::invalid_argument("map '" + map.quantity + "': arrows need u and v of the values' size");
  }
  constexpr int kMaxArrowsPerSide = 32;
  const int stride = std::max(1, (std::max(map.values.rows, map.values.cols) + kMaxArrowsPerSide - 1) / kMaxArrowsPerSide);
  const int nx = (map.values.cols + stride - 1) / stride, ny = (map.values.rows + stride - 1) / stride;
  std::vector<std::vector<PLFLT>> u(nx, std::vector<PLFLT>(ny, 0.0)), v(nx, std::vector<PLFLT>(ny, 0.0));
  for (int c = 0; c < nx; ++c) {
    for (int r = 0; r < ny; ++r) {
      const double du = map.u_px.at<double>(r * stride, c * stride), dv = map.v_px.at<double>(r * stride, c * stride);
      if (!std::isfinite(du) || !std::isfinite(dv)) continue;  // zero length: PLplot draws nothing there
      u[c][r] = du;
      v[c][r] = dv;
    }
  }
  std::vector<const PLFLT*> u_rows(nx), v_rows(nx);
  for (int c = 0; c < nx; ++c) {
    u_rows[c] = u[c].data();
    v_rows[c] = v[c].data();
  }
  GridTransform transform{map.x0_px, map.y0_px, map.step_px * stride, scale};
  plcol0(kInk);
  plvect(u_rows.data(), v_rows.data(), nx, ny, 0.0, grid_to_world, &transform);
}

void check_map_input(const MapField& map, std::optional<double> px_per_mm) {
  if (map.values.empty() || map.values.channels() != 1) {
    throw std::invalid_argument("map '" + map.quantity + "' has no single-channel values to draw");
  }
  if (!(map.step_px > 0)) throw std::invalid_argument("map '" + map.quantity + "': step_px must be positive");
  if (px_per_mm && !(*px_per_mm > 0)) throw std::invalid_argument("px per mm must be positive");
}

// The grid as drawn: node (r, c) at (x0 + c·step, y0 + r·step) image px.
struct DrawnGrid {
  cv::Mat values;  // CV_64F
  cv::Mat masked;  // CV_8U, non-zero where the node holds no measurement
  double x0 = 0, y0 = 0, step = 0;
  int block = 1;  // the map's cells per drawn cell along each side
};

// 255 where the map's mask is set or its value is not finite.
cv::Mat not_measured(const MapField& map, const cv::Mat& values) {
  cv::Mat masked = cv::Mat::zeros(values.size(), CV_8U);
  if (!map.mask.empty()) {
    if (map.mask.size() != values.size()) throw std::invalid_argument("map mask and values differ in size");
    cv::Mat m;
    map.mask.convertTo(m, CV_8U);
    masked = m != 0;
  }
  for (int r = 0; r < values.rows; ++r) {
    for (int c = 0; c < values.cols; ++c) {
      if (!std::isfinite(values.at<double>(r, c))) masked.at<std::uint8_t>(r, c) = 255;
    }
  }
  return masked;
}

// Each block × block square of the grid as one drawn node at its centre.
void average_blocks(DrawnGrid& grid) {
  const cv::Mat& values = grid.values;
  const cv::Mat& masked = grid.masked;
  const int block = grid.block;
  const int rows = (values.rows + block - 1) / block, cols = (values.cols + block - 1) / block;
  cv::Mat coarse(rows, cols, CV_64F, cv::Scalar(0)), coarse_masked(rows, cols, CV_8U, cv::Scalar(0));
  for (int R = 0; R < rows; ++R) {
    for (int C = 0; C < cols; ++C) {
      double sum = 0;
      int known = 0, total = 0;
      for (int r = R * block; r < std::min(values.rows, (R + 1) * block); ++r) {
        for (int c = C * block; c < std::min(values.cols, (C + 1) * block); ++c) {
          ++total;
          if (masked.at<std::uint8_t>(r, c)) continue;
          sum += values.at<double>(r, c);
          ++known;
        }
      }
      // A block is drawn as data only when every cell in it was measured: a mean over measured and
      // not-measured cells would show a value where there is none.
      if (known == total && known > 0) {
        coarse.at<double>(R, C) = sum / known;
      } else {
        coarse_masked.at<std::uint8_t>(R, C) = 255;
      }
    }
  }
  grid.values = coarse;
  grid.masked = coarse_masked;
  grid.x0 += 0.5 * (block - 1) * grid.step;
  grid.y0 += 0.5 * (block - 1) * grid.step;
  grid.step *= block;
}

// A fine grid (a per-pixel temperature field) is averaged over blocks for
// drawing, so the figure stays light; the CSV keeps every cell.
DrawnGrid drawn_grid(const MapField& map) {
  DrawnGrid grid;
  map.values.convertTo(grid.values, CV_64F);
  grid.masked = not_measured(map, grid.values);
  grid.x0 = map.x0_px;
  grid.y0 = map.y0_px;
  grid.step = map.step_px;
  grid.block = (std::max(grid.values.rows, grid.values.cols) + kMaxDrawnCells - 1) / kMaxDrawnCells;
  if (grid.block > 1) average_blocks(grid);
  return grid;
}

// The values the colours span: the measured ones, symmetric about zero when
// they have both signs, never of zero width.
struct ColourScale {
  Range range;
  bool any_data = false;
  bool signed_values = false;  // drawn with the diverging map, white at zero
};

ColourScale colour_scale(const DrawnGrid& grid) {
  ColourScale scale;
  Range& range = scale.range;
  for (int r = 0; r < grid.values.rows; ++r) {
    for (int c = 0; c < grid.values.cols; ++c) {
      if (!grid.masked.at<std::uint8_t>(r, c)) range.add(grid.values.at<double>(r, c));
    }
  }
  scale.any_data = !range.empty();
  if (!scale.any_data) range = {0, 1};
  scale.signed_values = scale.any_data && range.low < 0 && range.high > 0;
  if (scale.signed_values) range = {-std::max(-range.low, range.high), std::max(-range.low, range.high)};
  if (range.high - range.low < 1e-9)
    range = {range.low - 0.5 * std::max(1e-3, std::abs(range.low) * 0.01),
             range.high + 0.5 * std::max(1e-3, std::abs(range.high) * 0.01)};
  return scale;
}

// Contour levels at multiples of the spacing; widened when there would be too many.
struct ContourLevels {
  double spacing = 0;
  bool widened = false;
  std::vector<PLFLT> levels;
};

ContourLevels contour_levels(double requested_spacing, const ColourScale& colours) {
  ContourLevels contours;
  contours.spacing = requested_spacing > 0 ? requested_spacing : 0;
  const Range& range = colours.range;
  if (contours.spacing > 0 && colours.any_data) {
    while ((range.high - range.low) / contours.spacing > kMaxContours) {
      contours.spacing *= 2;
      contours.widened = true;
    }
    for (double level = std::ceil(range.low / contours.spacing) * contours.spacing;
         level <= range.high && contours.levels.size() < 200; level += contours.spacing) {
      contours.levels.push_back(level);
    }
  }
  return contours;
}

// The plot's window: the whole image (its pixel centres on whole numbers), in mm when a scale is given.
struct MapAxes {
  double scale = 1;  // world units per image px
  const char* unit = "px";
  double wx0 = 0, wx1 = 0, wy0 = 0, wy1 = 0;
};

MapAxes map_axes(const MapField& map, std::optional<double> px_per_mm) {
  MapAxes axes;
  axes.scale = px_per_mm ? 1.0 / *px_per_mm : 1.0;
  axes.unit = px_per_mm ? "mm" : "px";
  const cv::Size extent = map.image_size_px.empty()
                              ? cv::Size(static_cast<int>(std::ceil(map.x0_px + map.step_px * map.values.cols)),
                                         static_cast<int>(std::ceil(map.y0_px + map.step_px * map.values.rows)))
                              : map.image_size_px;
  axes.wx0 = -0.5 * axes.scale;
  axes.wx1 = (extent.width - 0.5) * axes.scale;
  axes.wy0 = -0.5 * axes.scale;
  axes.wy1 = (extent.height - 0.5) * axes.scale;
  return axes;
}

// Everything the drawing needs, worked out before it starts.
struct MapPlot {
  DrawnGrid grid;
  ColourScale colours;
  ContourLevels contours;
  std::vector<PLFLT> edges;  // kBands + 1 colour band edges
  std::vector<MeasuredBlock> blocks;
  MapAxes axes;
  std::vector<std::vector<PLFLT>> z;  // the drawn values as PLplot indexes grids: [x][y]
};

MapPlot map_plot(const MapField& map, double contour_spacing, std::optional<double> px_per_mm) {
  MapPlot plot;
  plot.grid = drawn_grid(map);
  plot.colours = colour_scale(plot.grid);
  plot.blocks = measured_blocks(plot.grid.masked);
  plot.contours = contour_levels(contour_spacing, plot.colours);
  const Range& range = plot.colours.range;
  plot.edges.resize(kBands + 1);
  for (int i = 0; i <= kBands; ++i) plot.edges[i] = range.low + (range.high - range.low) * i / kBands;
  plot.axes = map_axes(map, px_per_mm);
  const cv::Mat& values = plot.grid.values;
  plot.z.assign(values.cols, std::vector<PLFLT>(values.rows));
  for (int c = 0; c < values.cols; ++c) {
    for (int r = 0; r < values.rows; ++r) plot.z[c][r] = values.at<double>(r, c);  // read only inside measured blocks
  }
  return plot;
}

std::string map_caption(const MapField& map, const MapPlot& plot, const std::string& when) {
  const DrawnGrid& grid = plot.grid;
  std::string caption = fmt::format(
      "{} ({}){}{}. Colour: value (bar on the right); black lines: contours every {:.3g} {}{}; hatched "
      "grey: masked or not measured ({} of {} cells), where no value is shown and no contour is drawn (bands and "
      "contours are computed from measured cells only); markers: thermocouple positions. Axes in {} from the image's "
      "top-left pixel, y pointing down.",
      map.quantity, map.unit, when, map.source.empty() ? "" : ", " + map.source, plot.contours.spacing, map.unit,
      plot.contours.widened ? " (widened from the requested spacing to keep the map readable)" : "",
      cv::countNonZero(grid.masked), grid.values.total(), plot.axes.unit);
  if (!plot.colours.any_data) caption += " Every cell is masked: nothing was measured.";
  if (grid.block > 1) {
    caption += fmt::format(
        " Drawn averaged over {0}×{0} cells of the {1}×{2} grid, a block with any cell not measured hatched (the CSV "
        "holds every cell).",
        grid.block, map.values.cols, map.values.rows);
  }
  if (plot.colours.signed_values) caption += " Colour: blue below zero, red above, white at zero.";
  if (map.arrows) {
    caption += " Arrows: the measured displacement (u, v) on a thinned grid, scaled so the longest spans about "
               "one arrow spacing; none where nothing was measured.";
  }
  return caption;
}

// The square a drawn node stands for, as a polygon for plfill.
struct Cell {
  std::array<PLFLT, 4> x, y;
};

Cell cell_at(const MapPlot& plot, int r, int c) {
  const DrawnGrid& g = plot.grid;
  const double scale = plot.axes.scale;
  const double half = 0.5 * g.step * scale;
  const double cx = (g.x0 + c * g.step) * scale, cy = (g.y0 + r * g.step) * scale;
  return {{cx - half, cx + half, cx + half, cx - half}, {cy - half, cy - half, cy + half, cy + half}};
}

// The measured nodes on the bands' edge, each a cell in its own colour.
void draw_edge_cells(const MapPlot& plot) {
  const Range& range = plot.colours.range;
  for (int r = 0; r < plot.grid.values.rows; ++r) {
    for (int c = 0; c < plot.grid.values.cols; ++c) {
      if (!needs_own_cell(plot.grid.masked, r, c)) continue;
      Cell cell = cell_at(plot, r, c);
      plcol1((plot.grid.values.at<double>(r, c) - range.low) / (range.high - range.low));
      plfill(4, cell.x.data(), cell.y.data());
    }
  }
}

// Colour bands and contours, each computed inside the measured blocks only.
void draw_bands_and_contours(const MapPlot& plot) {
  const DrawnGrid& g = plot.grid;
  const double scale = plot.axes.scale;
  for (const auto& b : plot.blocks) {
    // The block's nodes as a PLplot matrix of its own ([x][y]: columns of z from c0, rows from r0).
    std::vector<const PLFLT*> columns;
    for (int c = b.c0; c <= b.c1; ++c) columns.push_back(plot.z[c].data() + b.r0);
    plshades(columns.data(), b.c1 - b.c0 + 1, b.r1 - b.r0 + 1, nullptr, (g.x0 + b.c0 * g.step) * scale,
             (g.x0 + b.c1 * g.step) * scale, (g.y0 + b.r0 * g.step) * scale, (g.y0 + b.r1 * g.step) * scale,
             plot.edges.data(), kBands + 1, 0, 0, 0, plfill, 1, nullptr, nullptr);
  }
  const std::vector<PLFLT>& levels = plot.contours.levels;
  if (levels.empty()) return;
  const int nx = g.values.cols, ny = g.values.rows;
  std::vector<const PLFLT*> z_rows(nx);
  for (int c = 0; c < nx; ++c) z_rows[c] = plot.z[c].data();
  GridTransform transform{g.x0, g.y0, g.step, scale};
  plcol0(kInk);
  plwidth(1);
  for (const auto& b : plot.blocks) {  // kx, lx, ky, ly: the block's node range, 1-based
    plcont(z_rows.data(), nx, ny, b.c0 + 1, b.c1 + 1, b.r0 + 1, b.r1 + 1, levels.data(),
           static_cast<PLINT>(levels.size()), grid_to_world, &transform);
  }
}

// Masked cells: grey, hatched.
void draw_masked_cells(const MapPlot& plot) {
  for (int r = 0; r < plot.grid.values.rows; ++r) {
    for (int c = 0; c < plot.grid.values.cols; ++c) {
      if (!plot.grid.masked.at<std::uint8_t>(r, c)) continue;
      Cell cell = cell_at(plot, r, c);
      plpsty(0);
      plcol0(kMaskFill);
      plfill(4, cell.x.data(), cell.y.data());
      plpsty(3);
      plcol0(kMaskHatch);
      plfill(4, cell.x.data(), cell.y.data());
    }
  }
}

void draw_colour_bar(const MapField& map, const MapPlot& plot) {
  const std::string bar_label = pl_text(fmt::format("{} ({})", map.quantity, map.unit));
  const PLINT label_opts[] = {PL_COLORBAR_LABEL_RIGHT};
  const char* labels[] = {bar_label.c_str()};
  const char* axis_opts[] = {"bcvtm"};
  const PLFLT ticks[] = {0};
  const PLINT sub_ticks[] = {0};
  const PLINT n_values[] = {kBands + 1};
  const PLFLT* value_rows[] = {plot.edges.data()};
  PLFLT bar_width = 0, bar_height = 0;
  plschr(0, 0.8);
  plcolorbar(&bar_width, &bar_height, PL_COLORBAR_SHADE, PL_POSITION_RIGHT | PL_POSITION_OUTSIDE | PL_POSITION_VIEWPORT,
             0.02, 0, 0.04, 1.0, kBackground, kInk, 1, 0, 0, 0, 0, 1, label_opts, labels, 1, axis_opts, ticks,
             sub_ticks, n_values, value_rows);
  plschr(0, 1);
}

void draw_map(const MapField& map, const std::vector<MapMarker>& markers, const MapPlot& plot,
              const std::string& title) {
  const MapAxes& a = plot.axes;
  if (plot.colours.signed_values) use_diverging_colour_map();
  const double aspect = (a.wy1 - a.wy0) / (a.wx1 - a.wx0);
  plvpas(0.11, 0.80, 0.10, 0.92, aspect);
  plwind(a.wx0, a.wx1, a.wy1, a.wy0);  // y down, as in the image
  // Outside the grid nothing was evaluated: grey background first.
  plcol0(kMaskFill);
  const std::array<PLFLT, 4> bx{a.wx0, a.wx1, a.wx1, a.wx0}, by{a.wy0, a.wy0, a.wy1, a.wy1};
  plfill(4, bx.data(), by.data());
  plpsty(0);
  draw_edge_cells(plot);
  draw_bands_and_contours(plot);
  draw_masked_cells(plot);
  plpsty(0);
  if (map.arrows) draw_arrows(map, a.scale);
  if (cv::countNonZero(plot.grid.masked) > 0) draw_mask_legend();
  draw_markers(markers, a.scale, {a.wx0, a.wx1}, {a.wy0, a.wy1});
  plcol0(kInk);
  plbox("bcnst", 0, 0, "bcnstv", 0, 0);
  const std::string x_label = fmt::format("x ({})", a.unit), y_label = fmt::format("y ({}, down)", a.unit);
  pllab(x_label.c_str(), y_label.c_str(), title.c_str());
  draw_colour_bar(map, plot);
}

}  // namespace

FigureFiles write_map_figure(const MapField& map, double contour_spacing, const std::vector<MapMarker>& markers,
                             std::optional<double> px_per_mm, const FigureSize& size, const fs::path& base) {
  check_map_input(map, px_per_mm);
  const MapPlot plot = map_plot(map, contour_spacing, px_per_mm);
  FigureFiles files = files_for(base);
  // A pair evaluated outside a run has no time to state.
  const std::string when = map.time_s ? fmt::format(" at t = {:.1f} s", *map.time_s) : std::string();
  files.title = map.quantity + when;
  files.caption = map_caption(map, plot, when);
  render_png_and_svg(files, size, [&] { draw_map(map, markers, plot, pl_text(files.title)); });
  return files;
}

}  // namespace bosfuse::report
