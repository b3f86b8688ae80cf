#include "fusion/cross_correlation.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>
#include <utility>

#include "fusion/adaptive_refinement.h"
#include "fusion/for_rows.h"
#include "fusion/image_input.h"
#include "fusion/memory_budget.h"
#include "fusion/vector_uncertainty.h"

namespace bosfuse::fusion {
namespace {

struct PreparedPair {
  cv::Mat reference;    // CV_32F, [0,1]
  cv::Mat measurement;  // CV_32F, [0,1]; the inside of measurement_storage
  // The measurement with `measurement_border_px` replicated pixels on every
  // side: the first pass searches past the image's edge, and reads it here
  // in place instead of a copy of the whole image with its border.
  cv::Mat measurement_storage;
  int measurement_border_px = 0;
  // With a B-spline interpolator, what the deformation samples: each
  // image's spline coefficients (the reference's for symmetric deformation only).
  cv::Mat measurement_coefficients, reference_coefficients;
  cv::Mat mask_integral;  // CV_32S integral of the 0/1 exclusion mask; empty without mask
  cv::Mat excluded;       // CV_8U, non-zero excluded; empty without mask
  cv::Rect roi;
  cv::Point full_roi_origin;  // top-left of the whole ROI in these (possibly cropped) coordinates
};

void check_inputs(const cv::Mat& reference, const cv::Mat& measurement, const cv::Mat& mask,
                  const XcorrOptions& options) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  check_image_pair(reference, measurement, mask);
  check_window_fits(options.window_px_per_pass().front(), effective_roi(options.roi, reference.size()).size());
}

// The reference (or the part `crop` of it) as the evaluator works on it;
// coordinates in the result are relative to the crop. The measurement is
// left for prepare_measurement. A colour image's conversion is warned of
// into `warnings` (nullptr: silently), here and in prepare_measurement.
PreparedPair prepare_reference(const cv::Mat& reference, const cv::Mat& mask, const XcorrOptions& options,
                               cv::Rect crop, std::vector<std::string>* warnings) {
  PreparedPair pair;
  pair.reference = to_grey_unit_float(reference(crop), "reference", warnings);
  const cv::Rect full_roi = effective_roi(options.roi, reference.size());
  pair.roi = (full_roi & crop) - crop.tl();
  pair.full_roi_origin = full_roi.tl() - crop.tl();
  if (options.passes > 1 && options.deform && options.symmetric_deformation && needs_coefficients(options.interpolator)) {
    bspline_coefficients(pair.reference, options.interpolator, pair.reference_coefficients);
  }
  if (!mask.empty()) pair.excluded = to_exclusion_mask(mask(crop));
  if (!pair.excluded.empty()) {
    cv::Mat ones;
    cv::threshold(pair.excluded, ones, 0, 1, cv::THRESH_BINARY);
    cv::integral(ones, pair.mask_integral, CV_32S);
  }
  return pair;
}

// The `border_px` outermost pixels of `storage` on each side set to the
// nearest pixel inside them, as clamped coordinates would read it.
void replicate_border(cv::Mat& storage, int border_px) {
  const int last_row = storage.rows - 1 - border_px, last_col = storage.cols - 1 - border_px;
  for (int y = border_px; y <= last_row; ++y) {
    float* row = storage.ptr<float>(y);
    std::fill(row, row + border_px, row[border_px]);
    std::fill(row + last_col + 1, row + storage.cols, row[last_col]);
  }
  for (int y = 0; y < border_px; ++y) {
    storage.row(border_px).copyTo(storage.row(y));
    storage.row(last_row).copyTo(storage.row(last_row + 1 + y));
  }
}

// Into the pair's measurement buffer, reused when it has the size already,
// with a border as wide as the first pass's search.
void prepare_measurement(const cv::Mat& measurement, cv::Rect crop, std::vector<std::string>* warnings,
                         const XcorrOptions& options, PreparedPair& pair) {
  const int b = options.search_radius_px(0);
  create_large_image(pair.measurement_storage, crop.height + 2 * b, crop.width + 2 * b, CV_32F);
  pair.measurement_border_px = b;
  pair.measurement = pair.measurement_storage(cv::Rect(b, b, crop.width, crop.height));
  to_grey_unit_float(measurement(crop), "measurement", warnings, pair.measurement);
  replicate_border(pair.measurement_storage, b);
  if (options.passes > 1 && options.deform && needs_coefficients(options.interpolator)) {
    bspline_coefficients(pair.measurement, options.interpolator, pair.measurement_coefficients);
  }
}

// Both images, converted silently (a probe's caller warns of colour once).
PreparedPair prepare_silently(const cv::Mat& reference, const cv::Mat& measurement, const cv::Mat& mask,
                              const XcorrOptions& options, cv::Rect crop) {
  PreparedPair pair = prepare_reference(reference, mask, options, crop, nullptr);
  prepare_measurement(measurement, crop, nullptr, options, pair);
  return pair;
}

// Top-left corner of a window of `n` px centred at (x, y), kept inside the ROI.
cv::Point window_origin(double x_px, double y_px, int n, cv::Rect roi) {
  const int x0 = static_cast<int>(std::floor(x_px - (n - 1) / 2.0 + 1e-9));
  const int y0 = static_cast<int>(std::floor(y_px - (n - 1) / 2.0 + 1e-9));
  return {std::clamp(x0, roi.x, roi.x + roi.width - n), std::clamp(y0, roi.y, roi.y + roi.height - n)};
}

bool window_masked(const PreparedPair& pair, cv::Rect window, double max_fraction, double x_px, double y_px) {
  if (pair.excluded.empty()) return false;
  const cv::Point centre(static_cast<int>(std::floor(x_px)), static_cast<int>(std::floor(y_px)));
  if (pair.excluded.at<std::uint8_t>(centre)) return true;
  const auto& s = pair.mask_integral;
  const int count = s.at<int>(window.y + window.height, window.x + window.width) -
                    s.at<int>(window.y, window.x + window.width) - s.at<int>(window.y + window.height, window.x) +
                    s.at<int>(window.y, window.x);
  return count > max_fraction * window.area();
}

// A header over part of an image that does not share its reference count:
// taking ROIs of the same image from both threads for every window would
// make them fight over one atomic counter.
cv::Mat view(const cv::Mat& image, cv::Rect r) {
  return cv::Mat(r.height, r.width, image.type(), const_cast<uchar*>(image.ptr(r.y) + r.x * image.elemSize()),
                 image.step);
}

struct PassInput {
  int window_px = 16;
  int radius_px = 1;
  double on_bound_px = 0.5;              // a peak further out in either axis lies on the search bound
  double min_peak_ratio = 1;             // a peak of a lower ratio is not told from noise
  const GridField* predictor = nullptr;  // null in the first pass
  bool shift_whole_pixels = false;       // no deformation: offset each window by its rounded predictor
  cv::Mat warped;                        // measurement resampled over `region`
  cv::Mat warped_reference;              // symmetric deformation: the reference, resampled the other way
  cv::Rect region;
  // Each reference window's mean and energy, when cached: node (row, col)
  // of this pass is entry (row0 + stride·row)·cols + col0 + stride·col (the
  // coarse first pass takes every other node of the full grid's).
  const WindowStats* reference_stats = nullptr;
  int stats_row0 = 0, stats_col0 = 0, stats_stride = 1, stats_cols = 0;

  std::size_t stats_index(int row, int col) const {
    return static_cast<std::size_t>(stats_row0 + stats_stride * row) * stats_cols + stats_col0 + stats_stride * col;
  }
  const WindowStats* stats_at(int row, int col) const {
    return reference_stats ? reference_stats + stats_index(row, col) : nullptr;
  }
  const cv::Mat* refine = nullptr;  // adaptive refinement: only nodes marked 1 here are evaluated
  // Where each node's integer peak is kept (the field's size), for the
  // uncertainty of the final pass; null where no one reads it.
  std::int8_t* peak_dx = nullptr;
  std::int8_t* peak_dy = nullptr;
  // The pass is known to be the final one: each vector's σ is estimated as
  // it is measured, while its windows are in cache (a sweep afterwards
  // reads 128 MB of a 16 MP frame's images again).
  bool uncertainty_now = false;
  // σ's factor for the predictor's noise the vector carries (vector_uncertainty.h).
  double predictor_noise_gain = 1;
};

// Where a node's windows lie: the reference window, the search patch in the
// pass's warped image (its top-left the window's, shifted by −radius and
// the whole-pixel offset) and the shift the pass measures from.
struct NodeWindows {
  cv::Rect window;
  cv::Rect search;
  double base_u = 0, base_v = 0;
};

NodeWindows node_windows(const PreparedPair& pair, const PassInput& in, int row, int col,
                         const DisplacementVector& vec) {
  const int n = in.window_px, r = in.radius_px;
  NodeWindows w;
  w.window = cv::Rect(window_origin(vec.x_px, vec.y_px, n, pair.roi), cv::Size(n, n));
  w.base_u = in.predictor ? in.predictor->u_px.at<double>(row, col) : 0.0;
  w.base_v = in.predictor ? in.predictor->v_px.at<double>(row, col) : 0.0;
  cv::Point offset_px(0, 0);
  if (in.shift_whole_pixels) {
    offset_px = {static_cast<int>(std::lround(w.base_u)), static_cast<int>(std::lround(w.base_v))};
    w.base_u = offset_px.x;
    w.base_v = offset_px.y;
  }
  w.search = cv::Rect(w.window.x + offset_px.x - r - in.region.x, w.window.y + offset_px.y - r - in.region.y, n + 2 * r,
                      n + 2 * r);
  return w;
}

cv::Mat reference_window_of(const PreparedPair& pair, const PassInput& in, cv::Rect window) {
  return in.warped_reference.empty() ? view(pair.reference, window)
                                     : view(in.warped_reference, window - in.region.tl());
}

// σu, σv of a node from its reference window and the measurement window at
// its integer peak (dx, dy). A window whose deformed samples reach past the
// image read replicated border pixels there: a mismatch that is no
// independent pixel noise nor the warp's, so its statistics keep the
// per-pixel sum. σ then carries the predictor's noise (vector_uncertainty.h).
VectorUncertainty node_uncertainty(const PreparedPair& pair, const PassInput& in, const NodeWindows& w, int dx,
                                   int dy) {
  const int n = in.window_px, r = in.radius_px;
  const cv::Rect at_peak(w.search.x + r + dx, w.search.y + r + dy, n, n);
  // The interpolator's half-width (Lanczos4: 4 px) and the deformation's reach.
  const int reach = 4 + static_cast<int>(std::ceil(std::max(std::abs(w.base_u), std::abs(w.base_v))));
  const cv::Rect image(0, 0, pair.reference.cols, pair.reference.rows);
  const cv::Rect read(w.window.x - reach, w.window.y - reach, n + 2 * reach, n + 2 * reach);
  const bool inside_image = (read & image) == read;
  const cv::Mat reference_window = reference_window_of(pair, in, w.window);
  return with_predictor_noise(correlation_statistics(reference_window, view(in.warped, at_peak), inside_image),
                              in.predictor_noise_gain);
}

// Whether a fitted peak is a measurement: kBeyondSearch when it lies
// within half a pixel of the pass's search bound in either axis, before or
// after the sub-pixel fit (`on_bound_px` is that bound less 0.5 px: the true
// shift may lie past it, and a peak there is as often a neighbour's tail as
// the shift); kNoPeak when its ratio to the second peak (the highest local
// maximum outside its 3×3, not its own flank: a 6 px dot's peak is broader
// than 3×3) is too low to tell it from the noise of the plane.
VectorFlag peak_verdict(const CorrelationPeak& peak, const SubpixelOffset& offset, double on_bound_px,
                        double min_peak_ratio) {
  const double integer_px = std::max(std::abs(peak.dx), std::abs(peak.dy));
  const double fitted_px = std::max(std::abs(peak.dx + offset.dx_px), std::abs(peak.dy + offset.dy_px));
  if (integer_px > on_bound_px || !(fitted_px <= on_bound_px)) return VectorFlag::kBeyondSearch;
  if (!(peak.separate_ratio >= min_peak_ratio)) return VectorFlag::kNoPeak;
  return VectorFlag::kOk;
}

// Whether the predictor carries a node's window more than a quarter of it
// past the measurement's edge: what it would match there was never imaged
// (the border is replicated), and a peak in it is noise.
bool displaced_past_image(const PreparedPair& pair, const NodeWindows& w, int window_px) {
  const double slack_px = window_px / 4.0;
  const double x0 = w.window.x + w.base_u, y0 = w.window.y + w.base_v;
  return x0 < -slack_px || y0 < -slack_px || x0 + window_px > pair.measurement.cols + slack_px ||
         y0 + window_px > pair.measurement.rows + slack_px;
}

void evaluate_node(const PreparedPair& pair, const PassInput& in, const XcorrOptions& options, int row, int col,
                   std::size_t node, WindowCorrelator& correlator, CorrelationPlane& plane, DisplacementVector& vec) {
  const int r = in.radius_px;
  const NodeWindows w = node_windows(pair, in, row, col, vec);
  vec.u_px = vec.v_px = vec.peak_ratio = 0;
  vec.sigma_u_px = vec.sigma_v_px = 0;
  if (window_masked(pair, w.window, options.max_masked_fraction, vec.x_px, vec.y_px)) {
    vec.flag = VectorFlag::kMasked;
    return;
  }
  // After deformation the remaining shift is near 0: equal windows give an
  // unbiased peak there (see window_correlator.h).
  const auto pairing = in.predictor && options.deform ? WindowPairing::kEqualWindows : WindowPairing::kSearchArea;
  correlator.correlate(reference_window_of(pair, in, w.window), view(in.warped, w.search), r, options.correlation,
                       plane, pairing, in.stats_at(row, col));
  if (plane.reference_std < options.min_texture_std) {
    vec.flag = VectorFlag::kNoTexture;
    return;
  }
  if (in.predictor && displaced_past_image(pair, w, in.window_px)) {
    vec.flag = VectorFlag::kBeyondSearch;
    return;
  }
  const CorrelationPeak peak = find_peak(plane);
  if (!(peak.value > 0)) {
    vec.flag = VectorFlag::kNoPeak;  // flat or anti-correlated
    return;
  }
  if (std::abs(peak.dx) >= r || std::abs(peak.dy) >= r) {
    vec.flag = VectorFlag::kBeyondSearch;  // at the plane's edge: no fit, and the shift may lie past it
    return;
  }
  std::array<double, 9> c;
  for (int j = -1; j <= 1; ++j) {
    for (int i = -1; i <= 1; ++i) c[(j + 1) * 3 + i + 1] = plane.at(peak.dx + i, peak.dy + j);
  }
  const SubpixelOffset offset =
      subpixel_offset(c, pairing == WindowPairing::kEqualWindows ? options.refinement_subpixel : options.subpixel);
  vec.flag = peak_verdict(peak, offset, in.on_bound_px, in.min_peak_ratio);
  if (vec.flag != VectorFlag::kOk) return;
  vec.u_px = w.base_u + peak.dx + offset.dx_px;
  vec.v_px = w.base_v + peak.dy + offset.dy_px;
  vec.peak_ratio = peak.ratio;
  if (in.peak_dx) {
    in.peak_dx[node] = static_cast<std::int8_t>(peak.dx);
    in.peak_dy[node] = static_cast<std::int8_t>(peak.dy);
  }
  if (in.uncertainty_now) {
    const VectorUncertainty sigma = node_uncertainty(pair, in, w, peak.dx, peak.dy);
    vec.sigma_u_px = sigma.sigma_u_px;
    vec.sigma_v_px = sigma.sigma_v_px;
  }
}

// The bounding box of windows; "none" starts inverted across the ROI.
struct WindowBox {
  int x_min, y_min, x_max, y_max;
  static WindowBox none(cv::Rect roi) { return {roi.x + roi.width, roi.y + roi.height, roi.x, roi.y}; }
  void merge(const WindowBox& o) {
    *this = {std::min(x_min, o.x_min), std::min(y_min, o.y_min), std::max(x_max, o.x_max), std::max(y_max, o.y_max)};
  }
  void add(cv::Rect window) { merge({window.x, window.y, window.x + window.width, window.y + window.height}); }
};

// The union of the rows' boxes, grown by `r`.
cv::Rect grown_union(const std::vector<WindowBox>& rows, WindowBox all, int r) {
  for (const WindowBox& box : rows) all.merge(box);
  if (all.x_max <= all.x_min || all.y_max <= all.y_min) return {0, 0, 1, 1};
  return {all.x_min - r, all.y_min - r, all.x_max - all.x_min + 2 * r, all.y_max - all.y_min + 2 * r};
}

// Bounding box of every window of the pass, grown by the search radius.
cv::Rect pass_region(const PreparedPair& pair, const DisplacementField& field, int n, int r) {
  const cv::Rect& roi = pair.roi;
  const WindowBox empty = WindowBox::none(roi);
  // Each row's box on all cores (a 16 MP field has 250,000 nodes, a serial
  // loop over them idles the other core), then their union.
  std::vector<WindowBox> rows(static_cast<std::size_t>(field.rows), empty);
  for_rows(field.rows, [&](int row) {
    for (int col = 0; col < field.cols; ++col) {
      const auto& vec = field.at(row, col);
      if (vec.flag == VectorFlag::kOutOfRoi) continue;
      rows[static_cast<std::size_t>(row)].add({window_origin(vec.x_px, vec.y_px, n, roi), cv::Size(n, n)});
    }
  });
  return grown_union(rows, empty, r);
}

// A copy with new node values (cv::Mat copies share data, so this must not
// write into the original's); with `only`, at the nodes it marks alone.
GridField scaled(const GridField& field, double factor, const cv::Mat* only = nullptr) {
  GridField out{field.grid, {}, {}};
  if (!only) {
    field.u_px.convertTo(out.u_px, CV_64F, factor);
    field.v_px.convertTo(out.v_px, CV_64F, factor);
    return out;
  }
  out.u_px.create(field.u_px.size(), CV_64F);
  out.v_px.create(field.v_px.size(), CV_64F);
  for_marked(*only, [&](int row, int col) {
    out.u_px.at<double>(row, col) = factor * field.u_px.at<double>(row, col);
    out.v_px.at<double>(row, col) = factor * field.v_px.at<double>(row, col);
  });
  return out;
}

int max_abs_shift_px(const GridField& field) {
  if (field.u_px.empty()) return 0;
  double u_min, u_max, v_min, v_max;
  cv::minMaxLoc(field.u_px, &u_min, &u_max);
  cv::minMaxLoc(field.v_px, &v_min, &v_max);
  return static_cast<int>(std::ceil(std::max({std::abs(u_min), std::abs(u_max), std::abs(v_min), std::abs(v_max)}))) +
         1;
}

// Over the nodes `only` marks, when given (the others are known not to
// have changed).
double max_change_px(const DisplacementField& before, const DisplacementField& after, const cv::Mat* only = nullptr) {
  std::vector<double> row_change(static_cast<std::size_t>(after.rows), 0.0);
  for_row_runs(after.rows, after.cols, only, [&](int row, int first, int last) {
    double& change = row_change[static_cast<std::size_t>(row)];
    for (int col = first; col < last; ++col) {
      const auto &b = before.at(row, col), &a = after.at(row, col);
      if (!a.valid() || !b.valid()) continue;
      change = std::max({change, std::abs(a.u_px - b.u_px), std::abs(a.v_px - b.v_px)});
    }
  });
  return row_change.empty() ? 0.0 : *std::max_element(row_change.begin(), row_change.end());
}

// `to` = `from`, rows on all cores into the buffer `to` already has; only
// at the nodes `only` marks, when given (the rest of `to` is left as it
// was, for a reader of those nodes alone).
void copy_field(const DisplacementField& from, DisplacementField& to, const cv::Mat* only = nullptr) {
  to.rows = from.rows;
  to.cols = from.cols;
  to.vectors.resize(from.vectors.size());
  for_row_runs(from.rows, from.cols, only, [&](int row, int first, int last) {
    const std::ptrdiff_t begin = static_cast<std::ptrdiff_t>(row) * from.cols;
    std::copy(from.vectors.begin() + begin + first, from.vectors.begin() + begin + last,
              to.vectors.begin() + begin + first);
  });
}

// A correlator and its plane per thread, kept for the life of the thread:
// their buffers serve every window of every pass and frame.
struct CorrelatorScratch {
  WindowCorrelator correlator;
  CorrelationPlane plane;
};

CorrelatorScratch& thread_scratch() {
  thread_local CorrelatorScratch scratch;
  return scratch;
}

void run_pass(const PreparedPair& pair, const PassInput& in, const XcorrOptions& options, DisplacementField& field) {
  const int node_count = static_cast<int>(field.vectors.size());
  auto evaluate_range = [&](const cv::Range& range) {
    CorrelatorScratch& scratch = thread_scratch();
    for (int i = range.start; i < range.end; ++i) {
      if (in.refine && !in.refine->data[i]) continue;  // before the vector: most nodes are not selected
      auto& vec = field.vectors[static_cast<std::size_t>(i)];
      if (vec.flag == VectorFlag::kOutOfRoi) continue;
      evaluate_node(pair, in, options, i / field.cols, i % field.cols, static_cast<std::size_t>(i), scratch.correlator,
                    scratch.plane, vec);
    }
  };
  // A probe's few windows cost less than waking the other thread.
  if (node_count < 64) {
    evaluate_range(cv::Range(0, node_count));
    return;
  }
  cv::parallel_for_(cv::Range(0, node_count), evaluate_range, std::max(1.0, node_count / 256.0));
}

// σu, σv of the vectors the final pass `in` measured (kOk, and under
// adaptive refinement the selected ones), from the windows it correlated
// and, at the grid's outermost nodes, what their deformation left
// (vector_uncertainty.h); then the outliers it replaced get their
// neighbours' spread (outlier_filter.h).
void estimate_uncertainty(const PreparedPair& pair, const PassInput& in, DisplacementField& field) {
  if (in.uncertainty_now) {  // estimated as the pass measured
    add_held_deformation_uncertainty(*in.predictor, field, in.refine);
    estimate_replaced_uncertainty(field, in.refine);
    return;
  }
  const int node_count = static_cast<int>(field.vectors.size());
  auto estimate_range = [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      if (in.refine && !in.refine->data[i]) continue;
      auto& vec = field.vectors[static_cast<std::size_t>(i)];
      if (vec.flag != VectorFlag::kOk) continue;
      const NodeWindows w = node_windows(pair, in, i / field.cols, i % field.cols, vec);
      const VectorUncertainty sigma = node_uncertainty(pair, in, w, in.peak_dx[i], in.peak_dy[i]);
      vec.sigma_u_px = sigma.sigma_u_px;
      vec.sigma_v_px = sigma.sigma_v_px;
    }
  };
  if (node_count < 64) {
    estimate_range(cv::Range(0, node_count));
  } else {
    cv::parallel_for_(cv::Range(0, node_count), estimate_range, std::max(1.0, node_count / 256.0));
  }
  add_held_deformation_uncertainty(*in.predictor, field, in.refine);
  estimate_replaced_uncertainty(field, in.refine);
}

// The selection of the refinement passes and what the others keep.
struct AdaptivePasses {
  RefinementSelection selection;
  // Where the refinement passes' outlier test runs: the selection grown by
  // one node, so that every selected node ends as the whole field's test
  // would leave it (it replaces outliers in the selection alone).
  cv::Mat outlier_tested;
  SmoothingBuffers smoothing;
  // Selecting every node is full refinement, without the tiles' bookkeeping.
  bool active() const { return !selection.refine.empty() && selection.selected < selection.candidates; }
};

// What run_passes keeps between passes and, in an XcorrEvaluator, between
// frames: the warped images' buffers, and each reference window's mean and
// energy per window size for the nodes of the full grid (probes leave
// cache_reference_stats false and have them summed per window).
struct PassWorkspace {
  cv::Mat warped_storage, warped_reference_storage;
  bool cache_reference_stats = false;
  std::map<int, std::vector<WindowStats>> reference_stats;          // by window size
  std::vector<std::int8_t> peak_dx, peak_dy;  // the last pass's integer peaks, for its uncertainty
  DisplacementField previous_field;           // the field before a pass, for its change
  GridField predictor;                        // a refinement pass's, and its smoothing's scratch
  cv::Mat predictor_scratch;
  // Under adaptive refinement, the nodes a pass reads its predictor at, and
  // those grown by one node, which its smoothing reads.
  cv::Mat predicted_nodes, predicted_nodes_around;
  AdaptivePasses adaptive;  // adaptive refinement's selection and what it works in
};

// The top-left `size` of `storage`, which grows when too small: the regions
// of successive passes differ by a few pixels, and a fresh buffer for each
// would page-fault its 64 MB (16 MP) again.
cv::Mat reuse(cv::Mat& storage, cv::Size size) {
  if (storage.rows < size.height || storage.cols < size.width) {
    create_large_image(storage, std::max(storage.rows, size.height), std::max(storage.cols, size.width), CV_32F);
  }
  return storage(cv::Rect({0, 0}, size));
}

// The measurement over `region`, undeformed (a first pass, or shifts by
// whole pixels): in place where `region` lies within the measurement's
// border, else copied into `storage` with the border replicated as far as
// it reaches. Either holds the same pixels.
cv::Mat undeformed_measurement(const PreparedPair& pair, cv::Rect region, Interpolator interpolator, cv::Mat& storage) {
  const int b = pair.measurement_border_px;
  const cv::Rect bordered(-b, -b, pair.measurement.cols + 2 * b, pair.measurement.rows + 2 * b);
  if ((region & bordered) == region) return pair.measurement_storage(region + cv::Point(b, b));
  cv::Mat out = reuse(storage, region.size());
  warp_region(pair.measurement, GridField{}, region, interpolator, out);
  return out;
}

// The statistics of the reference's window of `window_px` at every node of
// `field`, kept in the workspace (by window size): the node positions never
// change for an evaluator, so this runs at its first frame only.
const std::vector<WindowStats>& reference_stats_for(const PreparedPair& pair, const DisplacementField& field,
                                                    int window_px, PassWorkspace& workspace) {
  std::vector<WindowStats>& stats = workspace.reference_stats[window_px];
  if (stats.size() == field.vectors.size()) return stats;
  stats.assign(field.vectors.size(), WindowStats{});
  cv::parallel_for_(cv::Range(0, static_cast<int>(stats.size())), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      const auto& vec = field.vectors[static_cast<std::size_t>(i)];
      const cv::Point origin = window_origin(vec.x_px, vec.y_px, window_px, pair.roi);
      stats[static_cast<std::size_t>(i)] =
          window_stats(view(pair.reference, cv::Rect(origin, cv::Size(window_px, window_px))));
    }
  });
  return stats;
}

// A pass's measured vectors on their own grid.
struct MeasuredPass {
  DisplacementField field;
  GridGeometry grid;
};

// The first pass on every other node only, in x and y — a quarter of the
// correlations, and the widest searches — when the coarse windows still
// overlap; the rest of the field is interpolated for the next pass's
// predictor. Nodes are chosen by their lattice index counted from the ROI,
// so a probe's local grid picks the same nodes as the full field. None
// when the grid is too small for it (then the pass runs on every node).
struct CoarseGrid {
  GridGeometry grid;
  int row0 = 0, col0 = 0;  // its first node on the full grid
};

std::optional<CoarseGrid> coarse_first_pass_grid(const PreparedPair& pair, const GridGeometry& fine, int window_px,
                                                 const XcorrOptions& options) {
  if (!options.coarse_first_pass || 2 * fine.step_px > window_px) return std::nullopt;
  const double half = (options.window_px - 1) / 2.0;
  auto first_even = [&](double origin_px, int roi_origin_px) {
    const long index = std::lround((origin_px - (roi_origin_px + half)) / fine.step_px);
    return static_cast<int>(((index % 2) + 2) % 2);
  };
  CoarseGrid coarse{fine, 0, 0};
  coarse.col0 = first_even(fine.x0_px, pair.full_roi_origin.x);
  coarse.row0 = first_even(fine.y0_px, pair.full_roi_origin.y);
  coarse.grid.x0_px += coarse.col0 * fine.step_px;
  coarse.grid.y0_px += coarse.row0 * fine.step_px;
  coarse.grid.step_px = 2 * fine.step_px;
  coarse.grid.cols = (fine.cols - coarse.col0 + 1) / 2;
  coarse.grid.rows = (fine.rows - coarse.row0 + 1) / 2;
  if (coarse.grid.rows < 2 || coarse.grid.cols < 2) return std::nullopt;
  return coarse;
}

// `measured` gets the coarse field as measured (adaptive refinement's input).
void run_coarse_first_pass(const PreparedPair& pair, const CoarseGrid& coarse, PassInput in,
                           const XcorrOptions& options, PassWorkspace& workspace, DisplacementField& field,
                           MeasuredPass& measured) {
  DisplacementField sparse = field_on_grid(coarse.grid);
  for (int r = 0; r < coarse.grid.rows; ++r) {
    for (int c = 0; c < coarse.grid.cols; ++c) {
      sparse.at(r, c).flag = field.at(coarse.row0 + 2 * r, coarse.col0 + 2 * c).flag;
    }
  }
  in.region = pass_region(pair, sparse, in.window_px, in.radius_px);
  in.warped = undeformed_measurement(pair, in.region, options.interpolator, workspace.warped_storage);
  in.stats_row0 = coarse.row0;
  in.stats_col0 = coarse.col0;
  in.stats_stride = 2;
  run_pass(pair, in, options, sparse);
  if (options.replace_outliers) replace_outliers(sparse, options.outliers);
  const GridField predictor = predictor_from(sparse, coarse.grid);
  measured = {sparse, coarse.grid};
  if (field.vectors.empty()) return;
  // The field's nodes lie on its grid: each row's the same y, each column's the same x.
  std::vector<double> x_px(static_cast<std::size_t>(field.cols)), y_px(static_cast<std::size_t>(field.rows));
  for (int col = 0; col < field.cols; ++col) x_px[static_cast<std::size_t>(col)] = field.at(0, col).x_px;
  for (int row = 0; row < field.rows; ++row) y_px[static_cast<std::size_t>(row)] = field.at(row, 0).y_px;
  const GridSampler sample(predictor, x_px, y_px);
  for_rows(field.rows, [&](int row) {
    for (int col = 0; col < field.cols; ++col) {
      auto& vec = field.at(row, col);
      if (vec.flag == VectorFlag::kOutOfRoi) continue;
      const cv::Point2d p = sample.at(row, col);
      vec.u_px = p.x;
      vec.v_px = p.y;
      vec.peak_ratio = 0;
      vec.flag = VectorFlag::kOk;  // provisional: the next pass measures every node
    }
  });
}

// ---- Adaptive refinement (fusion/adaptive_refinement.h) ----

// Into `adaptive`, whose buffers an evaluator keeps between frames; the
// unselected nodes of `field` marked first-pass-only and smoothed (the
// refined nodes' predictor sees the smoothed values). No refinement pass
// changes them. What it selected is told in `notes`.
void select_for_refinement(const MeasuredPass& measured, DisplacementField& field, const GridGeometry& grid,
                           const XcorrOptions& options, AdaptivePasses& adaptive, std::vector<std::string>& notes) {
  const int context = refinement_context_nodes(options.window_px_per_pass()[1], options.search_radius_px(1),
                                               static_cast<int>(std::ceil(grid.step_px)));
  adaptive.selection =
      select_refinement(measured.field, measured.grid, field, grid, options.adaptive_threshold, context);
  for_rows(field.rows, [&](int row) {
    const std::uint8_t* refined = adaptive.selection.refine.ptr<std::uint8_t>(row);
    for (int col = 0; col < field.cols; ++col) {
      auto& vec = field.at(row, col);
      vec.first_pass_only = !refined[col] && vec.flag != VectorFlag::kOutOfRoi;
    }
  });
  smooth_unrefined(field, adaptive.selection.refine, options.adaptive_smoothing_nodes, adaptive.smoothing);
  cv::dilate(adaptive.selection.refine, adaptive.outlier_tested, cv::Mat::ones(3, 3, CV_8U));
  notes.push_back(fmt::format(
      "adaptive refinement: noise floor {:.4f} px, threshold {:.4f} px, {:.1f} % of the windows refined",
      adaptive.selection.noise_floor_px, adaptive.selection.threshold_px, 100 * adaptive.selection.fraction()));
}

// What a pass under adaptive refinement reads, in one visit of the selected
// nodes: its region (pass_region's box of their windows) and the parts of
// it the windows read (window and search, `reach_px` around it; masked
// windows read nothing), as runs of 32 px tiles along each row of tiles. A
// warp over the whole region would cost as much as the windows saved (and
// 64 px tiles warp 10 % more than these around a plume). Tiles are counted
// from the ROI's corner less the reach, known before the region is.
struct SelectedArea {
  cv::Rect region;
  std::vector<cv::Rect> tiles;
};

SelectedArea selected_area(const PreparedPair& pair, const DisplacementField& field, const cv::Mat& refine,
                           int window_px, int reach_px, const XcorrOptions& options) {
  constexpr int kTilePx = 32;
  const cv::Rect& roi = pair.roi;
  const cv::Point origin = roi.tl() - cv::Point(reach_px, reach_px);
  cv::Mat used = cv::Mat::zeros((roi.height + 2 * reach_px + kTilePx - 1) / kTilePx,
                                (roi.width + 2 * reach_px + kTilePx - 1) / kTilePx, CV_8U);
  const WindowBox empty = WindowBox::none(roi);
  std::vector<WindowBox> rows(static_cast<std::size_t>(field.rows), empty);
  // Node rows on both cores; neighbouring rows mark the same tiles, with the
  // same value, through atomic stores.
  for_marked_runs(refine, [&](int row, int first, int last) {
    int marked_to = -1;  // the run's windows lie left to right: tiles up to here are marked
    for (int col = first; col < last; ++col) {
      const auto& vec = field.at(row, col);
      if (vec.flag == VectorFlag::kOutOfRoi) continue;
      const cv::Rect window(window_origin(vec.x_px, vec.y_px, window_px, roi), cv::Size(window_px, window_px));
      rows[static_cast<std::size_t>(row)].add(window);
      if (window_masked(pair, window, options.max_masked_fraction, vec.x_px, vec.y_px)) continue;
      // Inside the ROI grown by the reach, as the window lies inside the ROI.
      const int tx0 = (window.x - reach_px - origin.x) / kTilePx;
      const int tx1 = (window.x + window_px + reach_px - 1 - origin.x) / kTilePx;
      const int ty0 = (window.y - reach_px - origin.y) / kTilePx;
      const int ty1 = (window.y + window_px + reach_px - 1 - origin.y) / kTilePx;
      for (int ty = ty0; ty <= ty1; ++ty) {
        for (int tx = std::max(tx0, marked_to + 1); tx <= tx1; ++tx)
          std::atomic_ref(used.at<std::uint8_t>(ty, tx)).store(1, std::memory_order_relaxed);
      }
      marked_to = std::max(marked_to, tx1);
    }
  });
  SelectedArea area{grown_union(rows, empty, reach_px), {}};
  for (int ty = 0; ty < used.rows; ++ty) {
    for_runs(used.ptr<std::uint8_t>(ty), used.cols, [&](int first, int last) {
      const cv::Rect run(origin.x + first * kTilePx, origin.y + ty * kTilePx, (last - first) * kTilePx, kTilePx);
      area.tiles.push_back(run & area.region);
    });
  }
  return area;
}

// warp_region over `region` into `out`, computed only on `tiles`: each
// pixel's value depends only on its position, so a tile equals that part of
// the whole warp. `out` is a reused buffer: outside the tiles it holds an
// earlier pass's pixels, which no selected window reads.
void warp_tiles(const cv::Mat& image, const GridField& field, cv::Rect region, const std::vector<cv::Rect>& tiles,
                Interpolator interpolator, cv::Mat& out) {
  cv::parallel_for_(cv::Range(0, static_cast<int>(tiles.size())), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      cv::Mat tile = out(tiles[i] - region.tl());
      warp_region(image, field, tiles[i], interpolator, tile);
    }
  });
}

// The nodes a deforming pass reads its predictor at — the selected ones
// and those the warp's tiles lie between — into `read`, and into `around`
// those grown by the nodes the predictor's smoothing reads.
void nodes_read(const std::vector<cv::Rect>& tiles, const GridGeometry& grid, const cv::Mat& selected, cv::Mat& read,
                cv::Mat& around) {
  selected.copyTo(read);
  for (const cv::Rect& tile : tiles) read(nodes_under(tile, grid)).setTo(1);
  mark_smoothing_taps(read, around);
}

// ---- end of adaptive refinement ----

// The part of the images a pass reads: its region, and under adaptive
// refinement the tiles of it the selected windows read.
struct PassArea {
  int window_px = -1, reach_px = -1;
  const cv::Mat* refine = nullptr;
  cv::Rect region;
  std::vector<cv::Rect> tiles;
  bool serves(int window, int reach, const cv::Mat* selection) const {
    return window == window_px && reach == reach_px && selection == refine;
  }
};

// Where the first pass measured (textured, unmasked windows in the ROI) and
// where of that it failed (peak on the bound or not told from noise), on
// its own grid: node (row, col) is node (row0 + stride·row, col0 +
// stride·col) of the full field.
struct FirstPassSupport {
  cv::Mat measured, failed, on_bound;  // CV_8U 0/1
  int row0 = 0, col0 = 0, stride = 1;
};

// The first pass's `field` into `support`, and its counts into `summary`.
void note_first_pass(const DisplacementField& field, int row0, int col0, int stride, FirstPassSupport& support,
                     EvaluationSummary& summary) {
  support = {cv::Mat::zeros(field.rows, field.cols, CV_8U), cv::Mat::zeros(field.rows, field.cols, CV_8U),
             cv::Mat::zeros(field.rows, field.cols, CV_8U), row0, col0, stride};
  for (int row = 0; row < field.rows; ++row) {
    for (int col = 0; col < field.cols; ++col) {
      const VectorFlag flag = field.at(row, col).flag;
      if (flag == VectorFlag::kMasked || flag == VectorFlag::kNoTexture || flag == VectorFlag::kOutOfRoi) continue;
      support.measured.at<std::uint8_t>(row, col) = 1;
      ++summary.first_pass_windows;
      const bool on_bound = flag == VectorFlag::kBeyondSearch;
      support.on_bound.at<std::uint8_t>(row, col) = on_bound;
      support.failed.at<std::uint8_t>(row, col) = on_bound || flag == VectorFlag::kNoPeak;
      if (on_bound) ++summary.first_pass_on_bound;
    }
  }
}

// A refinement pass measures only what remains within ±refine_shift_px of
// a predictor interpolated from the first pass: where most of the first
// pass's windows around a node (3×3 first-pass nodes; half or more) found no peak or one
// on the bound, that predictor is noise, and so is a peak around it, however
// clear. Such nodes are flagged (kBeyondSearch when any of those windows
// was on the bound, else kNoPeak). An isolated failure is not: its
// neighbours' predictor is good, and the refinement measures it.
void flag_unsupported(const FirstPassSupport& support, DisplacementField& field) {
  if (support.measured.empty()) return;
  cv::Mat measured, failed, on_bound;
  const cv::Size box(3, 3);
  cv::boxFilter(support.measured, measured, CV_32S, box, {-1, -1}, false, cv::BORDER_CONSTANT);
  cv::boxFilter(support.failed, failed, CV_32S, box, {-1, -1}, false, cv::BORDER_CONSTANT);
  cv::boxFilter(support.on_bound, on_bound, CV_32S, box, {-1, -1}, false, cv::BORDER_CONSTANT);
  auto nearest = [&](int index, int origin, int count) {
    const int n = static_cast<int>(std::lround(double(index - origin) / support.stride));
    return std::clamp(n, 0, count - 1);
  };
  for_rows(field.rows, [&](int row) {
    const int r = nearest(row, support.row0, measured.rows);
    for (int col = 0; col < field.cols; ++col) {
      auto& vec = field.at(row, col);
      if (vec.flag != VectorFlag::kOk && vec.flag != VectorFlag::kOutlierReplaced) continue;
      const int c = nearest(col, support.col0, measured.cols);
      if (2 * failed.at<int>(r, c) < measured.at<int>(r, c) || measured.at<int>(r, c) == 0) continue;
      vec.flag = on_bound.at<int>(r, c) > 0 ? VectorFlag::kBeyondSearch : VectorFlag::kNoPeak;
      vec.u_px = vec.v_px = vec.peak_ratio = vec.sigma_u_px = vec.sigma_v_px = 0;
      vec.first_pass_only = false;
    }
  });
}

// What run_passes carries from one pass to the next.
struct PassLoop {
  PassLoop(const PreparedPair& pair, const GridGeometry& grid, const XcorrOptions& options, PassWorkspace& workspace,
           DisplacementField& field, EvaluationSummary& summary)
      : pair(pair),
        grid(grid),
        options(options),
        workspace(workspace),
        field(field),
        summary(summary),
        windows(options.window_px_per_pass()) {}

  const PreparedPair& pair;
  const GridGeometry& grid;
  const XcorrOptions& options;
  PassWorkspace& workspace;
  DisplacementField& field;
  EvaluationSummary& summary;
  std::vector<int> windows;
  PassArea area;
  bool finish_now = false;
  std::optional<PassInput> final_pass;  // the pass the vectors come from, for their uncertainty
  FirstPassSupport support;

  bool more_than_one_pass() const { return windows.size() > 1; }
};

// What a pass is before anything is read for it: its window, search and
// peak test, and under adaptive refinement the nodes it evaluates.
PassInput pass_settings(const PassLoop& loop, int pass) {
  const XcorrOptions& options = loop.options;
  PassInput in;
  in.window_px = loop.windows[pass];
  in.radius_px = options.search_radius_px(pass);
  in.on_bound_px = options.on_bound_px(pass);
  // The first pass alone: a refinement pass measures a residual whose
  // support is the first pass's (flag_unsupported).
  in.min_peak_ratio = pass == 0 ? options.min_peak_ratio : 1.0;
  in.shift_whole_pixels = pass > 0 && !options.deform;
  in.refine = loop.workspace.adaptive.active() ? &loop.workspace.adaptive.selection.refine : nullptr;
  return in;
}

// The pass's region into `in`. What a pass reads depends on its window, its
// reach and the selection alone (node positions, the ROI and the mask hold
// for the frame): passes alike in these share it.
void read_area(PassLoop& loop, int reach_px, PassInput& in) {
  PassArea& area = loop.area;
  if (!area.serves(in.window_px, reach_px, in.refine)) {
    if (in.refine) {
      SelectedArea selected = selected_area(loop.pair, loop.field, *in.refine, in.window_px, reach_px, loop.options);
      area = {in.window_px, reach_px, in.refine, selected.region, std::move(selected.tiles)};
    } else {
      area = {in.window_px, reach_px, in.refine, pass_region(loop.pair, loop.field, in.window_px, reach_px), {}};
    }
  }
  in.region = area.region;
}

// A refinement pass's predictor from the field so far, into `in`; returns
// the nodes it was computed at (null: all of them). Under adaptive
// refinement a deforming pass reads its predictor at the selected nodes and
// under the warp's tiles alone: computed there.
const cv::Mat* predict(PassLoop& loop, int pass, PassInput& in) {
  if (pass == 0) return nullptr;
  PassWorkspace& workspace = loop.workspace;
  GridField& predictor = workspace.predictor;
  const cv::Mat* predicted = nullptr;
  if (in.refine && !in.shift_whole_pixels) {
    read_area(loop, in.radius_px, in);
    nodes_read(loop.area.tiles, loop.grid, *in.refine, workspace.predicted_nodes, workspace.predicted_nodes_around);
    predicted = &workspace.predicted_nodes;
  }
  if (!(predicted && predictor_at(loop.field, loop.grid, predictor, workspace.predicted_nodes_around))) {
    predictor_from(loop.field, loop.grid, predictor);
  }
  if (loop.options.deform && loop.options.smooth_predictor) {
    smooth_predictor(predictor, workspace.predictor_scratch, predicted);
  }
  in.predictor = &predictor;
  return predicted;
}

// The first pass on a coarser grid when there are refinement passes to
// follow and such a grid serves (coarse_first_pass_grid); false when the
// pass runs on the full grid.
bool ran_coarse_first_pass(PassLoop& loop, const PassInput& in) {
  const auto coarse = coarse_first_pass_grid(loop.pair, loop.grid, in.window_px, loop.options);
  if (!coarse) return false;
  MeasuredPass measured;
  run_coarse_first_pass(loop.pair, *coarse, in, loop.options, loop.workspace, loop.field, measured);
  note_first_pass(measured.field, coarse->row0, coarse->col0, 2, loop.support, loop.summary);
  loop.summary.passes_run = 1;
  loop.summary.window_px_per_pass.push_back(in.window_px);
  if (loop.options.adaptive_refinement) {
    select_for_refinement(measured, loop.field, loop.grid, loop.options, loop.workspace.adaptive, loop.summary.notes);
  }
  return true;
}

// The images the pass correlates over its region, into `in`: the
// measurement undeformed or warped by the predictor (and with symmetric
// deformation the reference the other way), on the selected tiles alone
// under adaptive refinement.
void warp_for_pass(const PassLoop& loop, const cv::Mat* predicted, bool warp, bool warp_reference,
                   Interpolator interpolator, PassInput& in) {
  const PreparedPair& pair = loop.pair;
  PassWorkspace& workspace = loop.workspace;
  const GridField& predictor = workspace.predictor;
  // A B-spline samples the image's coefficients (fast early passes' cubic, the image).
  const auto source = [&](const cv::Mat& image, const cv::Mat& coefficients) -> const cv::Mat& {
    return needs_coefficients(interpolator) ? coefficients : image;
  };
  auto warp_pass = [&](const cv::Mat& image, const GridField& by, cv::Mat& out) {
    if (in.refine) {
      warp_tiles(image, by, in.region, loop.area.tiles, interpolator, out);
    } else {
      warp_region(image, by, in.region, interpolator, out);
    }
  };
  if (!warp) {
    in.warped = undeformed_measurement(pair, in.region, interpolator, workspace.warped_storage);
  } else {
    in.warped = reuse(workspace.warped_storage, in.region.size());
    if (warp_reference) {
      // Each image moves half-way: both are interpolated at half the offset,
      // and the interpolation errors of the two largely cancel.
      in.warped_reference = reuse(workspace.warped_reference_storage, in.region.size());
      warp_pass(source(pair.measurement, pair.measurement_coefficients), scaled(predictor, 0.5, predicted), in.warped);
      warp_pass(source(pair.reference, pair.reference_coefficients), scaled(predictor, -0.5, predicted),
                in.warped_reference);
    } else {
      warp_pass(source(pair.measurement, pair.measurement_coefficients), predictor, in.warped);
    }
  }
}

// The pass itself over the images set up for it, its outliers replaced,
// and after the first pass the selection for adaptive refinement; its
// counts into the summary.
void measure_pass(PassLoop& loop, int pass, PassInput& in) {
  const XcorrOptions& options = loop.options;
  PassWorkspace& workspace = loop.workspace;
  AdaptivePasses& adaptive = workspace.adaptive;
  DisplacementField& field = loop.field;
  // Under adaptive refinement only the selected nodes change in a pass;
  // the rest keep the first pass's values.
  const cv::Mat* changeable = adaptive.active() ? &adaptive.selection.refine : nullptr;
  // Into a buffer kept between passes and frames: a fresh 12 MB copy (16 MP)
  // each pass would page-fault it anew.
  if (pass > 0) copy_field(field, workspace.previous_field, changeable);
  run_pass(loop.pair, in, options, field);
  if (pass == 0) note_first_pass(field, 0, 0, 1, loop.support, loop.summary);
  loop.final_pass = in;
  if (options.replace_outliers) {
    replace_outliers(field, options.outliers, adaptive.active() ? &adaptive.outlier_tested : nullptr, changeable);
  }
  if (pass == 0 && loop.more_than_one_pass() && options.adaptive_refinement) {
    select_for_refinement({field, loop.grid}, field, loop.grid, options, adaptive, loop.summary.notes);
  }
  loop.summary.passes_run = pass + 1;
  loop.summary.window_px_per_pass.push_back(in.window_px);
  if (pass > 0) loop.summary.last_change_px = max_change_px(workspace.previous_field, field, changeable);
}

// After a pass: whether the passes are done, because this one finished
// them or because it changed nothing (same window as the pass before): then
// one more pass with the accurate kernel finishes, unless this one had it.
bool passes_done(PassLoop& loop, int pass, Interpolator interpolator) {
  const XcorrOptions& options = loop.options;
  EvaluationSummary& summary = loop.summary;
  const bool same_window = pass > 0 && loop.windows[pass] == loop.windows[pass - 1];
  if (loop.finish_now) return true;
  if (same_window && options.convergence_px > 0 && summary.last_change_px < options.convergence_px) {
    summary.converged = true;
    if (interpolator == options.interpolator) return true;
    loop.finish_now = true;
  }
  return false;
}

// One pass, from its settings to its vectors; false when no pass follows.
bool run_one_pass(PassLoop& loop, int pass) {
  const XcorrOptions& options = loop.options;
  PassWorkspace& workspace = loop.workspace;
  PassInput in = pass_settings(loop, pass);
  const cv::Mat* predicted = predict(loop, pass, in);
  const int reach_px = in.radius_px + (in.shift_whole_pixels ? max_abs_shift_px(workspace.predictor) : 0);
  const bool warp = pass > 0 && options.deform;
  const bool warp_reference = warp && options.symmetric_deformation;
  if (workspace.cache_reference_stats && !warp_reference) {
    in.reference_stats = reference_stats_for(loop.pair, loop.field, in.window_px, workspace).data();
    in.stats_cols = loop.field.cols;
  }
  if (pass == 0 && loop.more_than_one_pass() && ran_coarse_first_pass(loop, in)) return true;
  read_area(loop, reach_px, in);
  if (options.estimate_uncertainty) {
    in.peak_dx = workspace.peak_dx.data();
    in.peak_dy = workspace.peak_dy.data();
  }
  // Passes before the last only feed the next pass's predictor: the
  // cheaper cubic kernel serves them as well; when they have converged, one
  // pass with the accurate kernel finishes.
  const bool last = pass + 1 == static_cast<int>(loop.windows.size()) || loop.finish_now;
  const Interpolator interpolator = options.fast_early_passes && !last ? Interpolator::kCubic : options.interpolator;
  in.uncertainty_now = options.estimate_uncertainty && last && warp;
  if (options.estimate_uncertainty) {
    in.predictor_noise_gain = predictor_noise_gain(in.window_px, options.step_px, options.smooth_predictor);
  }
  warp_for_pass(loop, predicted, warp, warp_reference, interpolator, in);
  measure_pass(loop, pass, in);
  return !passes_done(loop, pass, interpolator);
}

// After the last pass: the vectors' σ, the flags of nodes the first pass
// did not support, and the counts.
void finish_passes(PassLoop& loop) {
  const XcorrOptions& options = loop.options;
  EvaluationSummary& summary = loop.summary;
  const AdaptivePasses& adaptive = loop.workspace.adaptive;
  // Without deformation the final pass pairs a window with a larger search
  // patch, whose C(±1) read different pixels: the statistics of equal
  // windows do not describe that peak, and σ is left 0 (not estimated).
  if (options.estimate_uncertainty && loop.final_pass && loop.final_pass->predictor && options.deform) {
    estimate_uncertainty(loop.pair, *loop.final_pass, loop.field);
  }
  flag_unsupported(loop.support, loop.field);
  count_flags(loop.field, summary);
  summary.refined_fraction = adaptive.active() ? adaptive.selection.fraction() : summary.passes_run > 1 ? 1.0 : 0.0;
}

// Runs every pass over `field` (centres set; kOutOfRoi nodes are left alone),
// telling how into `summary` (its messages added to).
void run_passes(const PreparedPair& pair, const GridGeometry& grid, const XcorrOptions& options,
                PassWorkspace& workspace, DisplacementField& field, EvaluationSummary& summary) {
  summary.method = "xcorr";
  PassLoop loop(pair, grid, options, workspace, field, summary);
  workspace.adaptive.selection = {};  // none until this frame's first pass selects
  if (options.estimate_uncertainty) {
    workspace.peak_dx.resize(field.vectors.size());
    workspace.peak_dy.resize(field.vectors.size());
  }
  for (int pass = 0; pass < static_cast<int>(loop.windows.size()); ++pass) {
    if (!run_one_pass(loop, pass)) break;
  }
  finish_passes(loop);
}

// A probe's vector is the centre of its own small grid.
GridGeometry probe_grid(cv::Point2d point, const XcorrOptions& options, int context_nodes) {
  const double half = (options.window_px - 1) / 2.0;
  const double x = std::round(point.x - half) + half, y = std::round(point.y - half) + half;
  GridGeometry grid;
  grid.step_px = options.step_px;
  grid.x0_px = x - context_nodes * options.step_px;
  grid.y0_px = y - context_nodes * options.step_px;
  grid.rows = grid.cols = 2 * context_nodes + 1;
  return grid;
}

// The part of the image a probe's local grid can reach: its windows, the
// search around them, and the deformation's shift plus interpolation kernel.
// Computed in double and clipped before it becomes int: a probe point comes
// from a user or a stored run and may lie anywhere (even at -2^31 or NaN),
// where int pixel arithmetic would overflow.
cv::Rect probe_reach(const GridGeometry& grid, const XcorrOptions& options, cv::Size image_size) {
  const int first = options.window_px_per_pass().front();
  const double margin = first / 2 + 2 + std::max(options.search_radius_px(0), options.search_radius_px(1)) + 4 +
                        std::ceil(options.max_shift_px);
  const double x0 = std::max(std::floor(grid.x0_px) - margin, 0.0);
  const double y0 = std::max(std::floor(grid.y0_px) - margin, 0.0);
  const double x1 = std::min(std::ceil(grid.x0_px + (grid.cols - 1) * grid.step_px) + margin, image_size.width - 1.0);
  const double y1 = std::min(std::ceil(grid.y0_px + (grid.rows - 1) * grid.step_px) + margin, image_size.height - 1.0);
  if (!(x1 >= x0 && y1 >= y0)) return {};  // outside the image, or not a number
  return {static_cast<int>(x0), static_cast<int>(y0), static_cast<int>(x1 - x0) + 1, static_cast<int>(y1 - y0) + 1};
}

void flag_nodes_outside(const PreparedPair& pair, int window_px, DisplacementField& field) {
  for (auto& vec : field.vectors) {
    const double half = (window_px - 1) / 2.0;
    const bool inside = vec.x_px - half >= pair.roi.x - 1e-9 && vec.y_px - half >= pair.roi.y - 1e-9 &&
                        vec.x_px + half <= pair.roi.x + pair.roi.width - 1 + 1e-9 &&
                        vec.y_px + half <= pair.roi.y + pair.roi.height - 1 + 1e-9;
    if (!inside) vec.flag = VectorFlag::kOutOfRoi;
  }
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// One probe: its local grid, evaluated on the part of the images it can
// reach (the rest of a 16 MP frame is never converted or warped).
DisplacementVector evaluate_probe(const cv::Mat& reference, const cv::Mat& measurement, const cv::Mat& mask,
                                  cv::Point2d point, const XcorrOptions& options, int context,
                                  EvaluationSummary& summary) {
  const GridGeometry grid = probe_grid(point, options, context);
  const cv::Rect crop = probe_reach(grid, options, reference.size());
  DisplacementVector vec{
      grid.x0_px + context * grid.step_px, grid.y0_px + context * grid.step_px, 0, 0, 0, VectorFlag::kOutOfRoi};
  if (crop.area() == 0) return vec;
  const PreparedPair pair = prepare_silently(reference, measurement, mask, options, crop);
  PassWorkspace workspace;
  GridGeometry local_grid = grid;
  local_grid.x0_px -= crop.x;
  local_grid.y0_px -= crop.y;
  DisplacementField local = field_on_grid(local_grid);
  flag_nodes_outside(pair, options.window_px, local);
  if (local.at(context, context).flag == VectorFlag::kOutOfRoi) return vec;
  run_passes(pair, local_grid, options, workspace, local, summary);
  vec = local.at(context, context);
  vec.x_px += crop.x;
  vec.y_px += crop.y;
  return vec;
}

}  // namespace

std::string XcorrOptions::Validate() const {
  auto window_ok = [](int w) { return w >= 8 && w <= 128; };
  if (!window_ok(window_px)) return fmt::format("window must be 8 to 128 px, not {}", window_px);
  if (first_window_px != 0 && !window_ok(first_window_px)) {
    return fmt::format("first window must be 8 to 128 px, not {}", first_window_px);
  }
  if (first_window_px != 0 && first_window_px < window_px) return "first window must not be smaller than the final one";
  if (step_px < 1) return fmt::format("step must be at least 1 px, not {}", step_px);
  if (passes < 1 || passes > 20) return fmt::format("passes must be 1 to 20, not {}", passes);
  if (!(max_shift_px >= 0) || max_shift_px > 64) return "max shift must be 0 to 64 px";
  if (!(refine_shift_px >= 0) || refine_shift_px > 16) return "refine shift must be 0 to 16 px";
  if (2 * search_radius_px(1) >= window_px) return "refine shift must be below a quarter of the window";
  if (!(min_texture_std >= 0)) return "min texture std must not be negative";
  if (!(min_peak_ratio >= 1) || !std::isfinite(min_peak_ratio)) return "min peak ratio must be at least 1";
  if (const std::string problem = search.Validate(); !problem.empty()) return problem;
  if (!(max_masked_fraction >= 0 && max_masked_fraction <= 1)) return "max masked fraction must be 0 to 1";
  if (!(convergence_px >= 0)) return "convergence tolerance must not be negative";
  if (probe_context_nodes < -1) return "probe context must be -1 (exact) or at least 0 nodes";
  if (!(adaptive_threshold > 0) || !std::isfinite(adaptive_threshold)) {
    return "adaptive refinement threshold must be a positive number (times the noise floor)";
  }
  if (!(adaptive_smoothing_nodes >= 0 && adaptive_smoothing_nodes <= 16)) {
    return "adaptive refinement smoothing must be 0 to 16 nodes";
  }
  return outliers.Validate();
}

std::vector<int> XcorrOptions::window_px_per_pass() const {
  // Halve from the first window towards the final one, then stay there.
  std::vector<int> windows;
  int w = first_window_px > 0 ? first_window_px : window_px;
  for (int pass = 0; pass < passes; ++pass) {
    windows.push_back(std::max(w, window_px));
    w /= 2;
  }
  return windows;
}

int XcorrOptions::search_radius_px(int pass) const {
  const double shift = pass == 0 ? max_shift_px : refine_shift_px;
  return static_cast<int>(std::ceil(shift)) + 1;
}

double XcorrOptions::on_bound_px(int pass) const {
  // The first pass's bound is the user's or the scene's: half a pixel inside
  // it. A refinement pass searches a residual, whose fit the plane supports
  // up to half a pixel past ±refine_shift_px.
  return pass == 0 ? std::max(max_shift_px - 0.5, 0.5) : refine_shift_px + 0.5;
}

int XcorrOptions::exact_probe_context_nodes() const {
  // Per refinement pass a node's value depends on the nodes whose predictor
  // reaches its window, search and interpolation kernel (+1 for the bilinear
  // interpolation), on the outlier test's neighbours (+1) and on whether
  // those were outliers themselves (+1), and on the predictor smoothing (+1).
  // A coarse first pass reaches three coarse nodes, i.e. six grid nodes.
  const int first = window_px_per_pass().front();
  const int reach_px = first / 2 + search_radius_px(1) + 4;
  const int per_pass = (reach_px + step_px - 1) / step_px + 3 + (smooth_predictor ? 1 : 0);
  const int first_pass = coarse_first_pass && 2 * step_px <= first ? 7 : 3;
  return first_pass + (passes - 1) * per_pass;
}

struct XcorrEvaluator::State {
  cv::Mat reference, mask;  // as given; the pixels are shared
  XcorrOptions options;
  bool prepared = false;  // the rest is set at the first frame
  PreparedPair pair;      // the whole frame; its measurement buffer is reused
  GridGeometry grid;
  PassWorkspace workspace;
  bool colour_warned = false;
  bool bound_warned = false;  // a frame's search-bound warning is given once per evaluator
  std::optional<SearchRange> search;  // what find_search_range found (or was given) at the first frame
  bool search_known = false;          // search is options.known_search: the scene was not sampled
  // What preparing before any frame (search_range) had to say, for the first frame's summary.
  std::vector<std::string> pending_warnings, pending_notes;
};

namespace {

// At the first frame: the search bound and first window from the scene
// (or as an earlier evaluation found them), into the evaluator's options
// (later frames reuse them), and the measurement prepared again when its
// border must grow with the bound.
void find_search_range_once(const cv::Mat& measurement, XcorrEvaluator::State& s) {
  XcorrOptions& o = s.options;
  SearchStart start{o.max_shift_px, o.window_px_per_pass().front(), o.window_px, o.min_texture_std,
                    o.max_masked_fraction};
  s.search_known = o.known_search.has_value();
  s.search = s.search_known ? *o.known_search
                            : find_search_range(s.pair.reference, s.pair.measurement, s.pair.roi, s.pair.excluded,
                                                start, o.search);
  if (!s.search->widened) return;
  o.max_shift_px = s.search->max_shift_px;
  o.first_window_px = s.search->first_window_px;
  // Two passes at the final window at least: the halvings from a large first
  // window leave one, whose predictor still carries the coarse windows' error.
  int halvings = 0;
  for (int w = o.first_window_px; w / 2 >= o.window_px; w /= 2) ++halvings;
  o.passes = std::max(o.passes, halvings + 2);
  prepare_measurement(measurement, cv::Rect({0, 0}, s.reference.size()), nullptr, o, s.pair);
}

// Once, before the first frame allocates: later frames reuse its buffers.
void prepare_once(XcorrEvaluator::State& s) {
  if (s.prepared) return;
  if (std::string account = check_xcorr_memory(s.reference, s.mask, s.options); !account.empty()) {
    s.pending_notes.push_back(std::move(account));
  }
  s.pair = prepare_reference(s.reference, s.mask, s.options, cv::Rect({0, 0}, s.reference.size()),
                             &s.pending_warnings);
  s.grid = evaluation_grid(s.pair.roi, s.options.window_px, s.options.step_px);
  s.workspace.cache_reference_stats = true;
  s.prepared = true;
}

// The measurement into the prepared pair and, at the first frame, the search.
void prepare_frame(const cv::Mat& measurement, XcorrEvaluator::State& s) {
  prepare_measurement(measurement, cv::Rect({0, 0}, s.reference.size()),
                      s.colour_warned ? nullptr : &s.pending_warnings, s.options, s.pair);
  s.colour_warned = s.colour_warned || measurement.channels() > 1;
  if (s.options.find_search_range && !s.search) {
    find_search_range_once(measurement, s);
    if (s.search->widened) {
      s.pending_notes.push_back(s.search->Describe() + (s.search_known ? " (as stored)" : ""));
    }
  }
}

void describe_search(const XcorrEvaluator::State& s, EvaluationSummary& summary) {
  summary.max_shift_px = s.options.max_shift_px;
  summary.first_window_px = s.options.window_px_per_pass().front();
  summary.search_from_scene = s.search.has_value();
  summary.search_stored = s.search_known;
  summary.search_widened = s.search && s.search->widened;
  summary.search_beyond_reach = s.search && s.search->beyond_reach;
}

}  // namespace

XcorrEvaluator::XcorrEvaluator(const cv::Mat& reference, const XcorrOptions& options, const cv::Mat& mask)
    : state_(std::make_unique<State>()) {
  check_inputs(reference, reference, mask, options);
  state_->reference = reference;
  state_->mask = mask;
  state_->options = options;
}

XcorrEvaluator::~XcorrEvaluator() = default;
XcorrEvaluator::XcorrEvaluator(XcorrEvaluator&&) noexcept = default;
XcorrEvaluator& XcorrEvaluator::operator=(XcorrEvaluator&&) noexcept = default;

EvaluationResult XcorrEvaluator::evaluate(const cv::Mat& measurement) {
  const auto start = std::chrono::steady_clock::now();
  State& s = *state_;
  check_inputs(s.reference, measurement, s.mask, s.options);
  EvaluationResult result;
  EvaluationSummary& summary = result.summary;
  prepare_once(s);
  prepare_frame(measurement, s);
  summary.warnings = std::exchange(s.pending_warnings, {});
  summary.notes = std::exchange(s.pending_notes, {});
  result.field = field_on_grid(s.grid);
  run_passes(s.pair, s.grid, s.options, s.workspace, result.field, summary);
  describe_search(s, summary);
  if (std::string warning = search_bound_warning(summary); !warning.empty() && !s.bound_warned) {
    summary.warnings.push_back(std::move(warning));
    s.bound_warned = true;
  }
  result.summary.seconds = seconds_since(start);
  return result;
}

const std::optional<SearchRange>& XcorrEvaluator::search_range(const cv::Mat& measurement) {
  State& s = *state_;
  if (!s.options.find_search_range || s.search) return s.search;
  check_inputs(s.reference, measurement, s.mask, s.options);
  prepare_once(s);
  prepare_frame(measurement, s);
  return s.search;
}

const std::optional<SearchRange>& XcorrEvaluator::search_range() const { return state_->search; }

EvaluationResult XcorrEvaluator::probe(const cv::Mat& measurement, const std::vector<cv::Point2d>& points) {
  const auto start = std::chrono::steady_clock::now();
  const State& s = *state_;
  check_inputs(s.reference, measurement, s.mask, s.options);
  const XcorrOptions& options = s.options;
  const int context =
      options.probe_context_nodes < 0 ? options.exact_probe_context_nodes() : options.probe_context_nodes;
  XcorrOptions probe_options = options;
  probe_options.adaptive_refinement = false;  // a probe's grid is local already, too small for a noise floor
  EvaluationResult result;
  if (s.reference.channels() > 1 || measurement.channels() > 1) {
    result.summary.warnings.push_back(fmt::format("colour image converted to grey ({} and {} channels)",
                                                  s.reference.channels(), measurement.channels()));
  }
  result.summary.method = "xcorr-probe";
  result.field.rows = 1;
  result.field.cols = static_cast<int>(points.size());
  result.field.vectors.resize(points.size());
  std::vector<EvaluationSummary> summaries(points.size());
  // Probes are independent: one per task, on both cores.
  cv::parallel_for_(cv::Range(0, static_cast<int>(points.size())), [&](const cv::Range& range) {
    for (int i = range.start; i < range.end; ++i) {
      result.field.vectors[i] =
          evaluate_probe(s.reference, measurement, s.mask, points[i], probe_options, context, summaries[i]);
    }
  });
  for (const auto& summary : summaries) {
    result.summary.passes_run = std::max(result.summary.passes_run, summary.passes_run);
    if (!summary.window_px_per_pass.empty()) result.summary.window_px_per_pass = summary.window_px_per_pass;
  }
  count_flags(result.field, result.summary);
  result.summary.seconds = seconds_since(start);
  return result;
}

EvaluationResult evaluate_xcorr(const cv::Mat& reference, const cv::Mat& measurement, const XcorrOptions& options,
                                const cv::Mat& mask) {
  const auto start = std::chrono::steady_clock::now();
  EvaluationResult result = XcorrEvaluator(reference, options, mask).evaluate(measurement);
  result.summary.seconds = seconds_since(start);
  return result;
}

EvaluationResult probe_xcorr(const cv::Mat& reference, const cv::Mat& measurement,
                             const std::vector<cv::Point2d>& points, const XcorrOptions& options, const cv::Mat& mask) {
  const auto start = std::chrono::steady_clock::now();
  EvaluationResult result = XcorrEvaluator(reference, options, mask).probe(measurement, points);
  result.summary.seconds = seconds_since(start);
  return result;
}

}  // namespace bosfuse::fusion
