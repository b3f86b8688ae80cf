#pragma once
// The temperature field behind a displacement field. The displacement at
// each grid node gives the refractive-index gradient there (bos_geometry.h);
// integrating that gradient gives n, and Gladstone–Dale with the ideal gas
// gives density and temperature.
//
// Integration is least squares over the grid's edges: for neighbouring nodes
// i, j the difference n_j − n_i should equal the trapezoid estimate
// h·(g_i + g_j)/2 of the gradient component along the edge (h the node
// spacing at the flow plane). Its normal equations are the 5-point Poisson
// equation ∇²n = ∂x(∂n/∂x) + ∂y(∂n/∂y), discretised so that a field that is
// an exact gradient is recovered to the trapezoid rule's O(h²). The image
// border is Dirichlet: its nodes are ambient air, n = n0 — so the hot region
// must lie inside the evaluated area, except through edges declared open: a
// plume rising out of the top of the image leaves through it, and an open
// edge's nodes are unknowns held only by the measured gradients (the least-
// squares natural, Neumann, condition) instead of being forced to ambient.
//
// Masked and unmeasured nodes (flag other than kOk; kOutlierReplaced counts
// as measured unless excluded by the options) are interior unknowns with zero
// source: every edge touching one asks n_j − n_i = 0, but with a small weight
// (fill_weight), so the solve fills them harmonically from the measured
// surroundings while the measured edges alone decide the measured nodes —
// the gradient around a mask is not pulled flat by it, and no invented
// gradient enters. They are reported as not measured in the result.
//
// The solve is done for δn = n − n0 in double precision (n − 1 is ~3e-4, so
// solving for n itself would lose digits) by a sparse Cholesky factorisation:
// CHOLMOD's supernodal one by default (BLAS on dense blocks of the factor),
// Eigen's simplicial LDLᵀ as the alternative it is measured against.
//
// Weighted least squares (Rajendran, Zhang, Bhattacharya, Vlachos & Vlachos
// 2020, Exp. Fluids 61:239). When the displacement field carries standard
// uncertainties (sigma_u_px, sigma_v_px), each measured edge is weighted by
// 1/σ² of its target: the trapezoid mean of the two nodes' component along
// the edge has σ² = (σ_i² + σ_j²)/4, in px; the conversion to gradient units
// is one constant factor for every edge, so it cancels in the weights. The
// weights are taken relative to the median edge's (the median edge weighs 1,
// as every measured edge did before), so fill_weight keeps its meaning, and
// clamped to [1e-4, 1e4] so that one absurd σ cannot make the matrix
// singular in floating point. A field with no σ at all (every measured
// node 0) is solved unweighted, exactly as before. Mixed fields: a measured
// node whose σ is 0, negative or not finite (an evaluator or a replacement
// that did not estimate one) is given the median σ of that component over
// the field's measured nodes that have one — neither trusted infinitely (a
// 0 would be an infinite weight) nor discarded (it is a measurement); the
// summary counts such nodes. Measured, σ decides; unmeasured, fill_weight.
//
// Uncertainty of T (estimate_uncertainty): the solve is linear in the
// displacements, so its noise is the solve of the noise. The solver draws
// K sets of displacement noise, each node's u and v ±σ with random signs
// (zero mean, variance σ², its own absolute σ: the mean square estimates the
// variance as normal deviates would, with no more spread, and cheaper: the
// estimate on a 16 MP grid fell from ~2.9 to ~1.8 CPU-s with them), assembles their right-hand sides as the
// measurement's is assembled, and solves them with the factor it already holds (in blocks of columns, so CHOLMOD's
// supernodal solve works on dense blocks); the variance of δn at a node is the mean square of its K solutions. Chosen
// over sampling (AᵀWA)⁻¹ through the factor (z ~ N(0, I), Lᵀx = z) and over
// selected inversion because the trapezoid edges are not independent —
// each node's u enters two edges — so (AᵀWA)⁻¹ is not the estimator's
// covariance, while propagating the node noise is, whatever the weights
// (clamped, median-filled, or none); and it needs nothing of the factor but
// its solve, for both solvers. Its own relative error in σ is at most
// ~1/√(2K): 8.8 % for the default K = 64. σ of T is σ of δn times |dT/dn| = T/(n − 1)
// (the linearised Gladstone–Dale gas law). It is the random part only: the
// border's ambient is taken as exact (σ 0 there), and the systematic
// (Type B) parts — K, Z_D, magnification, ambient — are not in it. Where
// it is not a measurement's (unmeasured, filled nodes: the fill's error is
// no noise), not physical, or not estimated (option off, no σ in the
// field), σ is NaN, flagged by `measured`, `physical` and the summary.
//
// A run's frames share one grid and so one sparsity pattern; only the
// weights (which nodes are unmeasured, and their σ) and the right-hand side
// change. The TemperatureFieldSolver keeps what survives between frames: the
// ordering and symbolic analysis while the grid stays, and the numeric
// factor too while the weights stay the same, so such a frame costs only the
// two triangular solves. With weights from σ, which change every frame,
// a frame with the kept factor's unmeasured nodes but other σ is solved by
// conjugate gradients preconditioned by the kept factor (of an earlier
// frame's weights W₀) to the exact weighted solution of its own σ, to a
// relative residual of iterative_tolerance (1e-8: every node within 1e-6
// °C of a fresh factorisation's, measured 2e-8–6e-8 °C on 16 MP frames).
// The eigenvalues of the preconditioned matrix lie between the smallest and
// the largest ratio of an edge's new weight to its kept one, which bounds
// the iterations it can need; when that bound exceeds what a factorisation
// costs (15 iterations: σ moved ~10 % or more since the kept factor), or
// the iteration does not reach the tolerance, the frame is refactorised
// and its factor kept for the next ones. A frame whose σ of T is estimated
// is refactorised too, as the estimate solves with the factor itself (and
// anything else that needs (AᵀWA)⁻¹ must use a factor of the frame's own
// weights). Cost: docs/BENCHMARKS.md, "Weighted integration".
// recover_temperature_field is the one-shot form.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fusion/bos_geometry.h"
#include "fusion/displacement_field.h"
#include "fusion/field_warp.h"

namespace bosfuse::fusion {

// The sparse Cholesky behind the solve. Both give the same field (to
// rounding); the supernodal one is the faster on large grids.
enum class PoissonSolver { kCholmodSupernodal, kEigenSimplicial };

struct TemperatureFieldOptions {
  bool use_replaced_outliers = true;  // kOutlierReplaced vectors (neighbour medians) count as measurements
  int max_nodes = 4'000'000;          // bound on the linear system's size
  double fill_weight = 1e-3;          // weight of the zero-gradient edges at unmeasured nodes (measured: 1)
  // Image edges the heated air leaves through (not ambient); at least one edge must stay ambient.
  bool open_top = false, open_bottom = false, open_left = false, open_right = false;
  PoissonSolver solver = PoissonSolver::kCholmodSupernodal;
  // Weight the edges by the displacements' σ when the field has them (false: unweighted whatever σ says).
  bool weight_by_sigma = true;
  // Estimate each node's σ of T by propagating K noise draws (see above); off: sigma_c all NaN.
  bool estimate_uncertainty = false;
  int uncertainty_samples = 64;         // K, ≥ 8; σ's own relative error ~1/√(2K)
  std::uint64_t uncertainty_seed = 29;  // the draws' seed: the same field gives the same σ
  // A frame whose σ alone changed is solved by conjugate gradients on the kept factor to this relative
  // residual ‖AᵀWA·δn − b‖ / ‖b‖ (see the header); 0: refactorised instead, as before.
  double iterative_tolerance = 1e-8;

  std::string Validate() const;  // empty when valid
};

// Node values on the displacement field's grid, row-major.
struct TemperatureField {
  int rows = 0;
  int cols = 0;
  double x0_px = 0;  // centre of node (0, 0)
  double y0_px = 0;
  double step_px = 1;
  std::vector<double> temperature_c;     // NaN only where n came out ≤ 1 (flagged by `physical`)
  std::vector<double> refractive_index;  // n at each node
  std::vector<std::uint8_t> measured;    // 1: the node's displacement was a measurement
  std::vector<std::uint8_t> physical;    // 0: the solve gave n ≤ 1, no temperature
  // Standard uncertainty (random part) of T (°C) and of n at each node; NaN
  // where not estimated, not measured or not physical (see the header).
  std::vector<double> sigma_c;
  std::vector<double> sigma_refractive_index;

  std::size_t index(int row, int col) const { return static_cast<std::size_t>(row) * cols + col; }
  // Bilinear between nodes; nullopt outside the grid or next to an
  // unphysical node.
  std::optional<double> temperature_at(double x_px, double y_px) const;
  // σ of T there: the same bilinear weights applied to the nodes' σ — an
  // upper bound of the interpolated T's σ (equal when the nodes' errors are
  // fully correlated, as neighbours' nearly are); nullopt outside the grid
  // or next to a node without σ.
  std::optional<double> sigma_at(double x_px, double y_px) const;
};

struct TemperatureFieldSummary {
  std::size_t nodes = 0;
  std::size_t boundary_nodes = 0;
  std::size_t unknowns = 0;
  std::size_t unmeasured_nodes = 0;    // filled by the solve (masked, no texture, ...)
  std::size_t unphysical_nodes = 0;    // n ≤ 1: temperature NaN
  bool weighted = false;               // the edges were weighted by the displacements' σ
  std::size_t median_sigma_nodes = 0;  // measured nodes without a σ of their own, given the median's
  bool uncertainty_estimated = false;  // sigma_c holds values (option on and σ in the field)
  int uncertainty_samples = 0;         // K of the estimate
  double uncertainty_seconds = 0;      // of `seconds`, the part spent on the estimate
  int solver_iterations = 0;           // conjugate-gradient iterations on the kept factor; 0: solved directly
  double relative_residual = 0;        // theirs, at the end (≤ iterative_tolerance); 0 when solved directly
  double kept_factor_condition = 0;    // bound on cond(M⁻¹A) of the kept factor M for this frame; 0: not computed
  double min_c = 0;
  double max_c = 0;
  double seconds = 0;

  std::string brief_report() const;
};

struct TemperatureFieldResult {
  TemperatureField field;
  TemperatureFieldSummary summary;
};

// `displacement` must be a regular grid of at least 3×3 nodes (not a probe
// field): throws std::invalid_argument otherwise, or when the options are
// invalid.
TemperatureFieldResult recover_temperature_field(const DisplacementField& displacement, const BosGeometry& geometry,
                                                 const TemperatureFieldOptions& options = {});

// The temperature fields of a sequence of displacement fields, reusing the
// factorisation work between them (see the header's paragraph): hold one for
// a run's frames. Any grid is accepted; a different grid (size, origin,
// spacing) only costs a new analysis. Calls are serialised by a mutex, so
// frames finished on another thread may share it, one at a time.
class TemperatureFieldSolver {
 public:
  // Throws std::invalid_argument when the options are invalid.
  TemperatureFieldSolver(const BosGeometry& geometry, const TemperatureFieldOptions& options = {});
  ~TemperatureFieldSolver();
  TemperatureFieldSolver(const TemperatureFieldSolver&) = delete;
  TemperatureFieldSolver& operator=(const TemperatureFieldSolver&) = delete;

  // Same result and errors as recover_temperature_field.
  TemperatureFieldResult recover(const DisplacementField& displacement);

  // The analysis of the Poisson system for fields on `grid`, ahead of the
  // first recover() on it (the system's pattern does not depend on which
  // nodes are measured): a run can have it done beside its first frames'
  // evaluation. Throws as recover() would for the grid.
  void prepare(const GridGeometry& grid);

  // The fields recovered so far, and what they cost: symbolic analyses
  // (orderings) and numeric factorisations; the rest of the calls only solved.
  int fields() const;
  int analyses() const;
  int factorisations() const;
  int iterative_solves() const;  // solves (frames, probe σ) by conjugate gradients on an earlier frame's factor

  // The random σ of T (°C) of a weighted average Σ wᵢ Tᵢ of nodes of
  // `field`, the field recover() gave for `displacement` (a probe's
  // bilinear interpolation, a window's mean): exactly, not by draws. The
  // solve is linear, δn = A⁻¹ B d for the vectors' noise d (covariance
  // Σ = diag(σ²), as recover()'s draws take it), so with c the averaging
  // weights times dT/dn at each node, Var = Σ_k σ_k² ((Bᵀ A⁻¹ c)_k)²: one
  // solve with the kept factor and one pass over the edges, whatever the
  // weights. The neighbours' correlation through the solve is in it (their
  // errors are nearly equal), which the bilinear σ of sigma_at() bounds
  // from above. With the kept factor when it is this field's matrix, by
  // conjugate gradients on it when only σ moved (as the frame's own solve),
  // else factorised anew.
  // nullopt when the field has no σ, or a node of the average is not
  // measured or not physical; throws std::invalid_argument for nodes off
  // the grid or sizes that differ.
  std::optional<double> average_sigma_c(const DisplacementField& displacement, const TemperatureField& field,
                                        const std::vector<std::size_t>& nodes, const std::vector<double>& weights);

 private:
  friend TemperatureFieldResult recover_temperature_field(const DisplacementField&, const BosGeometry&,
                                                          const TemperatureFieldOptions&);
  struct State;
  BosGeometry geometry_;
  TemperatureFieldOptions options_;
  std::unique_ptr<State> state_;
};

}  // namespace bosfuse::fusion
