#pragma once
// DisplacementField is what an evaluator returns: one vector per
// interrogation window, at the window's centre, on a regular grid (or at the
// probe points in probe mode). Coordinates follow DESIGN.md: origin at the
// top-left pixel's centre, x right, y down; a feature at (x, y) in the
// reference appears at (x + u, y + v) in the measurement image.
//
// Every vector carries a flag saying why it is or is not a measurement, so a
// caller never has to guess what a NaN means: u and v are always finite (0
// where nothing could be measured), and `valid` is true only for kOk.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace bosfuse::fusion {

enum class VectorFlag : std::uint8_t {
  kOk = 0,               // measured, passed the outlier test
  kOutlierReplaced = 1,  // failed the normalized-median test; u, v are the median of its neighbours
  kNoTexture = 2,        // reference window too uniform to correlate (std below threshold)
  kMasked = 3,           // window centre or too much of the window under the mask
  kOutOfRoi = 4,         // window does not fit in the image / region of interest
  kNoPeak = 5,           // no correlation peak distinguishable from noise (flat, negative, or peak ratio too low)
  kBeyondSearch = 6,     // the peak lies on the search bound: the shift may lie beyond it
};

std::string to_string(VectorFlag flag);
// The flag to_string names `name`; false when it names none.
bool parse_vector_flag(std::string_view name, VectorFlag& flag);

struct DisplacementVector {
  double x_px = 0;  // window centre
  double y_px = 0;
  double u_px = 0;
  double v_px = 0;
  double peak_ratio = 0;  // first / second correlation peak; 0 when not measured
  VectorFlag flag = VectorFlag::kOk;
  // Adaptive refinement left it at the first pass's value (no displacement
  // above the noise floor around it): a measurement, but a coarser one.
  bool first_pass_only = false;
  // Standard uncertainty of u and v (px), estimated from the final pass's
  // windows; 0 where it is not estimated (not a measurement, or an
  // evaluator without an uncertainty estimate).
  double sigma_u_px = 0;
  double sigma_v_px = 0;

  bool valid() const { return flag == VectorFlag::kOk; }
};

struct DisplacementField {
  // Grid shape: rows × cols vectors in row-major order. A probe-mode field is
  // one row of `cols` probes.
  int rows = 0;
  int cols = 0;
  std::vector<DisplacementVector> vectors;

  DisplacementVector& at(int row, int col) { return vectors[static_cast<std::size_t>(row) * cols + col]; }
  const DisplacementVector& at(int row, int col) const { return vectors[static_cast<std::size_t>(row) * cols + col]; }
  std::size_t size() const { return vectors.size(); }
  std::size_t count(VectorFlag flag) const;
  std::size_t count_valid() const { return count(VectorFlag::kOk); }
};

}  // namespace bosfuse::fusion
