#include "fusion/temperature_field.h"

#include <fmt/format.h>

#include <Eigen/CholmodSupport>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <stdexcept>
#include <type_traits>

#include "fusion/evaluation.h"

namespace bosfuse::fusion {
namespace {

// Grid spacing and origin of a displacement field, checked to be regular.
struct GridLayout {
  double x0_px = 0, y0_px = 0, step_px = 1;
};

GridLayout grid_layout(const DisplacementField& field) {
  if (field.rows < 3 || field.cols < 3 || field.size() != static_cast<std::size_t>(field.rows) * field.cols) {
    throw std::invalid_argument("temperature field needs a displacement grid of at least 3x3 nodes");
  }
  const GridLayout layout{field.at(0, 0).x_px, field.at(0, 0).y_px, field.at(0, 1).x_px - field.at(0, 0).x_px};
  const double step_y = field.at(1, 0).y_px - field.at(0, 0).y_px;
  if (!(layout.step_px > 0) || std::abs(step_y - layout.step_px) > 1e-6) {
    throw std::invalid_argument("temperature field needs a regular grid with equal x and y spacing");
  }
  return layout;
}

bool is_measured(const DisplacementVector& v, const TemperatureFieldOptions& options) {
  return v.valid() || (options.use_replaced_outliers && v.flag == VectorFlag::kOutlierReplaced);
}

// A node on an edge held at ambient air.
bool on_ambient_border(const DisplacementField& f, int row, int col, const TemperatureFieldOptions& o) {
  return (row == 0 && !o.open_top) || (row == f.rows - 1 && !o.open_bottom) || (col == 0 && !o.open_left) ||
         (col == f.cols - 1 && !o.open_right);
}

// Every edge between neighbouring nodes of a rows×cols grid, once:
// add(i, j, along_x) with j the node right of i or below it.
template <typename Add>
void for_each_edge(int rows, int cols, Add add) {
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * cols + c;
      if (c + 1 < cols) add(i, i + 1, true);
      if (r + 1 < rows) add(i, i + cols, false);
    }
  }
}

// The least-squares system for δn at interior nodes: each edge i→j asks
// δn_j − δn_i = target with a weight, border nodes are fixed at δn = 0
// (ambient). The matrix depends only on the grid and on which nodes are
// measured (the weights), so it is assembled only when asked for.
class EdgeSystem {
 public:
  EdgeSystem(const std::vector<int>& unknown_index, int unknowns, bool with_matrix)
      : unknown_(unknown_index), rhs_(Eigen::VectorXd::Zero(unknowns)), with_matrix_(with_matrix) {
    if (with_matrix_) triplets_.reserve(static_cast<std::size_t>(unknowns) * 6);
  }

  void add_edge(std::size_t i, std::size_t j, double target, double weight) {
    const int ui = unknown_[i], uj = unknown_[j];
    if (ui >= 0) rhs_[ui] -= weight * target;
    if (uj >= 0) rhs_[uj] += weight * target;
    if (!with_matrix_) return;
    if (ui >= 0) triplets_.emplace_back(ui, ui, weight);
    if (uj >= 0) triplets_.emplace_back(uj, uj, weight);
    if (ui >= 0 && uj >= 0) {
      triplets_.emplace_back(ui, uj, -weight);
      triplets_.emplace_back(uj, ui, -weight);
    }
  }

  const Eigen::VectorXd& rhs() const { return rhs_; }
  Eigen::SparseMatrix<double> matrix() const {
    Eigen::SparseMatrix<double> a(rhs_.size(), rhs_.size());
    a.setFromTriplets(triplets_.begin(), triplets_.end());
    return a;
  }

 private:
  const std::vector<int>& unknown_;
  std::vector<Eigen::Triplet<double>> triplets_;
  Eigen::VectorXd rhs_;
  bool with_matrix_;
};

// The sparse Cholesky in its three steps, so that a sequence of frames can
// repeat only the later ones.
class Factorisation {
 public:
  virtual ~Factorisation() = default;
  virtual void analyse(const Eigen::SparseMatrix<double>& a) = 0;  // ordering, elimination tree
  virtual void factorise(const Eigen::SparseMatrix<double>& a) = 0;
  virtual Eigen::VectorXd solve(const Eigen::VectorXd& rhs) const = 0;
  virtual Eigen::MatrixXd solve_block(const Eigen::MatrixXd& rhs) const = 0;  // a column per right-hand side
};

template <class Decomposition>
class EigenFactorisation final : public Factorisation {
 public:
  explicit EigenFactorisation(bool nested_dissection) : nested_dissection_(nested_dissection) {}

  void analyse(const Eigen::SparseMatrix<double>& a) override {
    if constexpr (std::is_same_v<Decomposition, Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>>>) {
      // CHOLMOD's default takes AMD unless its fill looks bad, which it does
      // not on a grid; METIS' nested dissection is the better ordering for a
      // 2-D grid: each factorisation on the 16 MP grid took 0.5 s instead of
      // 1.0 s, but its analysis ~1.3 s instead of ~0.2 s — worth it only
      // when the analysis serves many frames (temperature_bench).
      if (nested_dissection_) {
        cholmod_common& common = decomposition_.cholmod();
        common.nmethods = 1;
        common.method[0].ordering = CHOLMOD_METIS;
      }
    }
    decomposition_.analyzePattern(a);
    if (decomposition_.info() != Eigen::Success)
      throw std::runtime_error("temperature field: Poisson matrix not analysed");
  }
  void factorise(const Eigen::SparseMatrix<double>& a) override {
    decomposition_.factorize(a);
    if (decomposition_.info() != Eigen::Success)
      throw std::runtime_error("temperature field: Poisson matrix not factorised");
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& rhs) const override {
    Eigen::VectorXd x = decomposition_.solve(rhs);
    if (decomposition_.info() != Eigen::Success) throw std::runtime_error("temperature field: Poisson solve failed");
    return x;
  }
  Eigen::MatrixXd solve_block(const Eigen::MatrixXd& rhs) const override {
    Eigen::MatrixXd x = decomposition_.solve(rhs);
    if (decomposition_.info() != Eigen::Success) throw std::runtime_error("temperature field: Poisson solve failed");
    return x;
  }

 private:
  Decomposition decomposition_;
  bool nested_dissection_;
};

// `nested_dissection`: the ordering for a factorisation repeated over many
// frames (CHOLMOD only; Eigen's is AMD).
std::unique_ptr<Factorisation> make_factorisation(PoissonSolver solver, bool nested_dissection) {
  using Matrix = Eigen::SparseMatrix<double>;
  switch (solver) {
    case PoissonSolver::kCholmodSupernodal:
      return std::make_unique<EigenFactorisation<Eigen::CholmodSupernodalLLT<Matrix>>>(nested_dissection);
    case PoissonSolver::kEigenSimplicial:
      return std::make_unique<EigenFactorisation<Eigen::SimplicialLDLT<Matrix>>>(nested_dissection);
  }
  throw std::invalid_argument("temperature field: unknown Poisson solver");
}

// An earlier frame's factor as the preconditioner of a conjugate-gradient
// solve (Eigen's preconditioner interface): the factor of M = AᵀW₀A serves
// a frame whose matrix AᵀWA has the same edges and other weights.
class KeptFactorPreconditioner {
 public:
  void use(const Factorisation* factorisation) { factorisation_ = factorisation; }
  template <typename Matrix>
  KeptFactorPreconditioner& analyzePattern(const Matrix&) { return *this; }
  template <typename Matrix>
  KeptFactorPreconditioner& factorize(const Matrix&) { return *this; }
  template <typename Matrix>
  KeptFactorPreconditioner& compute(const Matrix&) { return *this; }
  Eigen::VectorXd solve(const Eigen::VectorXd& residual) const { return factorisation_->solve(residual); }
  Eigen::ComputationInfo info() const { return factorisation_ ? Eigen::Success : Eigen::InvalidInput; }

 private:
  const Factorisation* factorisation_ = nullptr;
};

// For A = Σ wₑ aₑaₑᵀ and M = Σ w₀ₑ aₑaₑᵀ over the same edges, every
// Rayleigh quotient xᵀAx / xᵀMx is a weighted mean of the ratios wₑ/w₀ₑ, so
// the eigenvalues of M⁻¹A lie between the smallest and the largest ratio:
// their quotient bounds the preconditioned system's condition number.
double condition_bound(const std::vector<double>& weights, const std::vector<double>& kept_weights) {
  double smallest = std::numeric_limits<double>::infinity(), largest = 0;
  for (std::size_t e = 0; e < weights.size(); ++e) {
    const double ratio = weights[e] / kept_weights[e];
    smallest = std::min(smallest, ratio);
    largest = std::max(largest, ratio);
  }
  return largest / smallest;
}

// Conjugate gradients on `a` preconditioned by the kept factor; nullopt when
// it has not reached `tolerance` (relative residual) in `max_iterations`.
struct IterativeSolution {
  Eigen::VectorXd x;
  int iterations = 0;
  double relative_residual = 0;
};

std::optional<IterativeSolution> solve_preconditioned(const Eigen::SparseMatrix<double>& a, const Eigen::VectorXd& rhs,
                                                      const Factorisation& kept, double tolerance,
                                                      int max_iterations) {
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper, KeptFactorPreconditioner> cg;
  cg.preconditioner().use(&kept);
  cg.setTolerance(tolerance);
  cg.setMaxIterations(max_iterations);
  cg.compute(a);
  IterativeSolution solution{cg.solve(rhs), 0, 0};
  solution.iterations = static_cast<int>(cg.iterations());
  solution.relative_residual = cg.error();
  if (cg.info() != Eigen::Success || !(solution.relative_residual <= tolerance) || !solution.x.allFinite())
    return std::nullopt;
  return solution;
}

// What decides the sparsity pattern: a new grid needs a new analysis.
struct GridKey {
  int rows = 0, cols = 0;
  GridLayout layout;
  bool operator==(const GridKey& o) const {
    return rows == o.rows && cols == o.cols && layout.x0_px == o.layout.x0_px && layout.y0_px == o.layout.y0_px &&
           layout.step_px == o.layout.step_px;
  }
};

std::vector<std::uint8_t> measured_nodes(const DisplacementField& displacement,
                                         const TemperatureFieldOptions& options) {
  std::vector<std::uint8_t> measured(displacement.size());
  for (std::size_t i = 0; i < measured.size(); ++i) measured[i] = is_measured(displacement.vectors[i], options) ? 1 : 0;
  return measured;
}

bool has_sigma(double sigma_px) { return std::isfinite(sigma_px) && sigma_px > 0; }

double median_of(std::vector<double> values) {
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// The σ (px) of each measured node's u and v as the solve uses them: its
// own, or the field's median where it has none (see the header); empty when
// no measured node has one.
struct NodeSigmas {
  std::vector<double> u, v;
  std::size_t median_filled = 0;
  bool any() const { return !u.empty(); }
};

NodeSigmas node_sigmas(const DisplacementField& displacement, const std::vector<std::uint8_t>& measured) {
  std::vector<double> own_u, own_v;
  for (std::size_t i = 0; i < measured.size(); ++i) {
    if (!measured[i]) continue;
    if (has_sigma(displacement.vectors[i].sigma_u_px)) own_u.push_back(displacement.vectors[i].sigma_u_px);
    if (has_sigma(displacement.vectors[i].sigma_v_px)) own_v.push_back(displacement.vectors[i].sigma_v_px);
  }
  if (own_u.empty() && own_v.empty()) return {};
  const double median_u = median_of(own_u.empty() ? own_v : own_u), median_v = median_of(own_v.empty() ? own_u : own_v);
  NodeSigmas sigmas;
  sigmas.u.assign(measured.size(), 0.0);
  sigmas.v.assign(measured.size(), 0.0);
  for (std::size_t i = 0; i < measured.size(); ++i) {
    if (!measured[i]) continue;
    const DisplacementVector& vector = displacement.vectors[i];
    const bool own = has_sigma(vector.sigma_u_px) && has_sigma(vector.sigma_v_px);
    sigmas.u[i] = has_sigma(vector.sigma_u_px) ? vector.sigma_u_px : median_u;
    sigmas.v[i] = has_sigma(vector.sigma_v_px) ? vector.sigma_v_px : median_v;
    sigmas.median_filled += own ? 0 : 1;
  }
  return sigmas;
}

// Weights beyond these would only add rounding, not information.
constexpr double kMinRelativeWeight = 1e-4, kMaxRelativeWeight = 1e4;

// The weight of every edge in for_each_edge's order: fill_weight where an
// end is unmeasured; else 1, or with `sigmas` the median edge variance over
// this edge's (σ_i² + σ_j²) of the component along it, clamped.
std::vector<double> edge_weights(int rows, int cols, const std::vector<std::uint8_t>& measured,
                                 const NodeSigmas* sigmas, double fill_weight) {
  std::vector<double> weights;
  weights.reserve(2 * measured.size());
  constexpr double kFill = -1;  // marks a fill edge until the median is known
  for_each_edge(rows, cols, [&](std::size_t i, std::size_t j, bool along_x) {
    if (!measured[i] || !measured[j]) return weights.push_back(kFill);
    if (!sigmas) return weights.push_back(1.0);
    const std::vector<double>& s = along_x ? sigmas->u : sigmas->v;
    weights.push_back(s[i] * s[i] + s[j] * s[j]);
  });
  std::vector<double> variances;
  if (sigmas)
    std::copy_if(weights.begin(), weights.end(), std::back_inserter(variances), [](double w) { return w > 0; });
  const double median_variance = variances.empty() ? 1.0 : median_of(std::move(variances));
  for (double& w : weights) {
    if (w == kFill) {
      w = fill_weight;
    } else if (sigmas) {
      w = std::clamp(median_variance / w, kMinRelativeWeight, kMaxRelativeWeight);
    }
  }
  return weights;
}

// Random signs, ±1 with equal odds (Rademacher deviates): zero mean and
// unit variance, so the mean square of the solutions estimates the variance
// as normal deviates would, unbiased and with no more spread (Hutchinson
// 1990) — at 64 deviates per draw of the generator, where normal deviates
// took most of the estimate's time.
class RandomSigns {
 public:
  explicit RandomSigns(std::uint64_t seed) : random_(seed) {}
  double next() {
    if (left_ == 0) bits_ = random_(), left_ = 64;
    --left_;
    const double sign = (bits_ & 1) != 0 ? 1.0 : -1.0;
    bits_ >>= 1;
    return sign;
  }

 private:
  std::mt19937_64 random_;
  std::uint64_t bits_ = 0;
  int left_ = 0;
};

// The variance of δn at each unknown: the mean square of the solutions of
// `samples` draws of the displacement noise (u, v = ±σ at random at each
// measured node: the variance σ²), each assembled as the measurement's
// right-hand side is.
Eigen::VectorXd propagated_variance(const Factorisation& factorisation, const std::vector<int>& unknown, int unknowns,
                                    const DisplacementField& grid, const std::vector<std::uint8_t>& measured,
                                    const std::vector<double>& weights, const NodeSigmas& sigmas, double target_per_px,
                                    int samples, std::uint64_t seed) {
  constexpr int kBlock = 16;  // columns solved at once: dense blocks for the supernodal solve, 32 MB on 16 MP
  RandomSigns random(seed);
  std::vector<double> du(measured.size()), dv(measured.size());
  Eigen::VectorXd sum_of_squares = Eigen::VectorXd::Zero(unknowns);
  for (int done = 0; done < samples; done += kBlock) {
    const int width = std::min(kBlock, samples - done);
    Eigen::MatrixXd rhs(unknowns, width);
    for (int k = 0; k < width; ++k) {
      for (std::size_t i = 0; i < measured.size(); ++i) {
        du[i] = measured[i] ? sigmas.u[i] * random.next() : 0.0;
        dv[i] = measured[i] ? sigmas.v[i] * random.next() : 0.0;
      }
      EdgeSystem noise(unknown, unknowns, false);
      std::size_t edge = 0;
      for_each_edge(grid.rows, grid.cols, [&](std::size_t i, std::size_t j, bool along_x) {
        const double w = weights[edge++];
        if (!measured[i] || !measured[j]) return;
        noise.add_edge(i, j, target_per_px * 0.5 * (along_x ? du[i] + du[j] : dv[i] + dv[j]), w);
      });
      rhs.col(k) = noise.rhs();
    }
    sum_of_squares += factorisation.solve_block(rhs).rowwise().squaredNorm();
  }
  return sum_of_squares / samples;
}

// σ of n and T at each measured, physical node from δn's variance; the
// ambient border's δn is fixed (σ 0). dT/dn = −T/(n − 1) for the gas law.
void set_uncertainty(TemperatureField& field, const std::vector<int>& unknown, const Eigen::VectorXd& variance) {
  for (std::size_t i = 0; i < field.temperature_c.size(); ++i) {
    if (!field.measured[i] || !field.physical[i]) continue;
    const double sigma_n = unknown[i] >= 0 ? std::sqrt(std::max(variance[unknown[i]], 0.0)) : 0.0;
    field.sigma_refractive_index[i] = sigma_n;
    field.sigma_c[i] = (field.temperature_c[i] + kZeroCelsiusK) * sigma_n / (field.refractive_index[i] - 1);
  }
}

// The field and its summary from the solved δn.
TemperatureFieldResult field_from_solution(const DisplacementField& displacement, const GridLayout& layout,
                                           const BosGeometry& geometry, const std::vector<int>& unknown,
                                           const std::vector<std::uint8_t>& measured, const Eigen::VectorXd& delta_n) {
  TemperatureFieldResult result;
  TemperatureField& field = result.field;
  field.rows = displacement.rows;
  field.cols = displacement.cols;
  field.x0_px = layout.x0_px;
  field.y0_px = layout.y0_px;
  field.step_px = layout.step_px;
  field.temperature_c.resize(displacement.size());
  field.refractive_index.resize(displacement.size());
  field.measured = measured;
  field.physical.resize(displacement.size());
  field.sigma_c.assign(displacement.size(), std::numeric_limits<double>::quiet_NaN());
  field.sigma_refractive_index.assign(displacement.size(), std::numeric_limits<double>::quiet_NaN());
  auto& summary = result.summary;
  summary.nodes = displacement.size();
  summary.unknowns = static_cast<std::size_t>(delta_n.size());
  summary.boundary_nodes = displacement.size() - summary.unknowns;
  summary.min_c = std::numeric_limits<double>::infinity();
  summary.max_c = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < displacement.size(); ++i) {
    const double n = geometry.ambient_refractive_index() + (unknown[i] >= 0 ? delta_n[unknown[i]] : 0.0);
    const double t = geometry.temperature_c(n);
    field.refractive_index[i] = n;
    field.temperature_c[i] = t;
    field.physical[i] = std::isfinite(t) ? 1 : 0;
    summary.unmeasured_nodes += field.measured[i] ? 0 : 1;
    summary.unphysical_nodes += field.physical[i] ? 0 : 1;
    if (std::isfinite(t)) {
      summary.min_c = std::min(summary.min_c, t);
      summary.max_c = std::max(summary.max_c, t);
    }
  }
  if (summary.unphysical_nodes == summary.nodes) summary.min_c = summary.max_c = std::nan("");
  return result;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

std::string TemperatureFieldOptions::Validate() const {
  if (max_nodes < 9) return "max_nodes must be at least 9";
  if (!(fill_weight > 0 && fill_weight <= 1)) return "fill_weight must lie in (0, 1]";
  if (open_top && open_bottom && open_left && open_right) return "at least one image edge must be ambient air";
  if (solver != PoissonSolver::kCholmodSupernodal && solver != PoissonSolver::kEigenSimplicial) {
    return "solver must be kCholmodSupernodal or kEigenSimplicial";
  }
  if (uncertainty_samples < 8 || uncertainty_samples > 100'000) return "uncertainty_samples must lie in [8, 100000]";
  if (!(iterative_tolerance == 0 || (iterative_tolerance >= 1e-14 && iterative_tolerance <= 1e-6)))
    return "iterative_tolerance must be 0 (refactorise) or lie in [1e-14, 1e-6]";
  return {};
}

namespace {

// Bilinear between the nodes of a field's grid; nullopt outside it or next
// to a non-finite node value.
std::optional<double> bilinear(const TemperatureField& f, const std::vector<double>& values, double x_px, double y_px) {
  const double fx = (x_px - f.x0_px) / f.step_px, fy = (y_px - f.y0_px) / f.step_px;
  if (!(fx >= 0 && fy >= 0 && fx <= f.cols - 1 && fy <= f.rows - 1)) return std::nullopt;
  if (values.size() != static_cast<std::size_t>(f.rows) * f.cols) return std::nullopt;
  const int c0 = std::min(static_cast<int>(fx), f.cols - 2), r0 = std::min(static_cast<int>(fy), f.rows - 2);
  const double ax = fx - c0, ay = fy - r0;
  const double t00 = values[f.index(r0, c0)], t01 = values[f.index(r0, c0 + 1)];
  const double t10 = values[f.index(r0 + 1, c0)], t11 = values[f.index(r0 + 1, c0 + 1)];
  const double value = (1 - ay) * ((1 - ax) * t00 + ax * t01) + ay * ((1 - ax) * t10 + ax * t11);
  if (!std::isfinite(value)) return std::nullopt;
  return value;
}

}  // namespace

std::optional<double> TemperatureField::temperature_at(double x_px, double y_px) const {
  return bilinear(*this, temperature_c, x_px, y_px);
}

std::optional<double> TemperatureField::sigma_at(double x_px, double y_px) const {
  return bilinear(*this, sigma_c, x_px, y_px);
}

std::string TemperatureFieldSummary::brief_report() const {
  return fmt::format(
      "temperature field: {} nodes ({} on the ambient border, {} unmeasured filled, {} unphysical), {:.2f} .. {:.2f} "
      "degC, {}, {}, {}, {:.3f} s",
      nodes, boundary_nodes, unmeasured_nodes, unphysical_nodes, min_c, max_c,
      weighted ? fmt::format("weighted by sigma ({} nodes given the median sigma)", median_sigma_nodes) : "unweighted",
      uncertainty_estimated
          ? fmt::format("sigma of T from {} samples ({:.3f} s)", uncertainty_samples, uncertainty_seconds)
          : "no sigma of T",
      solver_iterations > 0 ? fmt::format("{} conjugate-gradient iterations on the kept factor (residual {:.1e})",
                                          solver_iterations, relative_residual)
                            : "solved directly",
      seconds);
}

namespace {

// δn of one frame, and how it was solved: iterations 0 when directly by a
// factor of its own weights.
struct FrameSolution {
  Eigen::VectorXd delta_n;
  int iterations = 0;
  double relative_residual = 0;
  double condition_bound = 0;  // of the kept factor for this frame's matrix; 0: not computed
};

// A conjugate-gradient iteration costs a solve with the factor and a
// product with the matrix; on the 16 MP grid a numeric factorisation costs
// about as much as 15 of them (temperature_bench), so more would cost more
// than refactorising.
constexpr int kMaxIterations = 15;

// Iterations that conjugate gradients needs at most to reduce the error (in
// the matrix's norm) by `tolerance` when the preconditioned condition number
// is at most `condition`: 2·ρᵏ ≤ tolerance, ρ = (√κ − 1)/(√κ + 1).
double iterations_bound(double condition, double tolerance) {
  const double root = std::sqrt(std::max(condition, 1.0));
  const double rate = (root - 1) / (root + 1);
  if (rate <= 0) return 1;
  return std::ceil(std::log(2 / tolerance) / -std::log(rate));
}

}  // namespace

// What a solver keeps between frames of one grid.
struct TemperatureFieldSolver::State {
  std::mutex mutex;
  std::optional<GridKey> grid;
  std::vector<int> unknown;  // node → unknown index, −1 on the ambient border
  int unknowns = 0;
  std::unique_ptr<Factorisation> factorisation;
  bool analysed = false;
  std::vector<std::uint8_t> factorised_for;  // the measured nodes of the factorised matrix; empty: none
  std::vector<double> factorised_weights;    // and its edge weights
  int fields = 0;
  int analyses = 0;
  int factorisations = 0;
  int iterative_solves = 0;
  bool one_shot = false;  // recover_temperature_field's: the cheaper analysis

  void start_grid(const GridKey& key, const DisplacementField& displacement, const TemperatureFieldOptions& options) {
    grid = key;
    unknown.assign(displacement.size(), -1);
    unknowns = 0;
    for (int r = 0; r < key.rows; ++r) {
      for (int c = 0; c < key.cols; ++c) {
        if (!on_ambient_border(displacement, r, c, options))
          unknown[static_cast<std::size_t>(r) * key.cols + c] = unknowns++;
      }
    }
    factorisation = make_factorisation(options.solver, !one_shot);
    analysed = false;
    factorised_for.clear();
    factorised_weights.clear();
  }

  // Under the lock: the grid's numbering of unknowns, set up anew when the
  // field's grid (`layout`, grid_layout's) is not the last one's.
  void use_grid(const DisplacementField& displacement, const GridLayout& layout,
                const TemperatureFieldOptions& options) {
    if (displacement.size() > static_cast<std::size_t>(options.max_nodes)) {
      throw std::invalid_argument(
          fmt::format("temperature field: {} nodes exceed max_nodes {}", displacement.size(), options.max_nodes));
    }
    const GridKey key{displacement.rows, displacement.cols, layout};
    if (!grid || !(*grid == key)) start_grid(key, displacement, options);
  }

  // The pattern's analysis (any matrix of the grid's pattern serves).
  void analyse(const Eigen::SparseMatrix<double>& a) {
    factorisation->analyse(a);
    analysed = true;
    ++analyses;
  }

  // δn of a frame whose matrix is not the kept factor's. With `may_iterate`
  // (the same unmeasured nodes, only σ changed) by conjugate gradients on
  // the kept factor when the weights moved little enough for it to converge
  // in fewer solves than a factorisation costs; else, or when it did not
  // converge, factorised anew, and that factor kept for the next frames.
  FrameSolution solve_new_weights(const Eigen::SparseMatrix<double>& a, const Eigen::VectorXd& rhs,
                                  const std::vector<std::uint8_t>& measured, const std::vector<double>& weights,
                                  bool may_iterate, double tolerance) {
    const double condition = may_iterate ? condition_bound(weights, factorised_weights) : 0;
    if (may_iterate && iterations_bound(condition, tolerance) <= kMaxIterations) {
      if (auto iterated = solve_preconditioned(a, rhs, *factorisation, tolerance, kMaxIterations)) {
        ++iterative_solves;
        return {std::move(iterated->x), iterated->iterations, iterated->relative_residual, condition};
      }
    }
    // Dropped first, so that a failed factorisation is not taken for a good one next frame.
    factorised_for.clear();
    factorised_weights.clear();
    if (!analysed) analyse(a);
    factorisation->factorise(a);
    ++factorisations;
    factorised_for = measured;
    factorised_weights = weights;
    return {factorisation->solve(rhs), 0, 0, condition};
  }
};

TemperatureFieldSolver::TemperatureFieldSolver(const BosGeometry& geometry, const TemperatureFieldOptions& options)
    : geometry_(geometry), options_(options), state_(std::make_unique<State>()) {
  if (const auto problem = options_.Validate(); !problem.empty()) throw std::invalid_argument(problem);
}

TemperatureFieldSolver::~TemperatureFieldSolver() = default;

int TemperatureFieldSolver::fields() const {
  std::lock_guard lock(state_->mutex);
  return state_->fields;
}

int TemperatureFieldSolver::analyses() const {
  std::lock_guard lock(state_->mutex);
  return state_->analyses;
}

int TemperatureFieldSolver::factorisations() const {
  std::lock_guard lock(state_->mutex);
  return state_->factorisations;
}

int TemperatureFieldSolver::iterative_solves() const {
  std::lock_guard lock(state_->mutex);
  return state_->iterative_solves;
}

void TemperatureFieldSolver::prepare(const GridGeometry& grid) {
  const DisplacementField field = field_on_grid(grid);
  const GridLayout layout = grid_layout(field);
  std::lock_guard lock(state_->mutex);
  State& state = *state_;
  state.use_grid(field, layout, options_);
  if (state.analysed) return;
  EdgeSystem system(state.unknown, state.unknowns, true);
  for_each_edge(field.rows, field.cols, [&](std::size_t i, std::size_t j, bool) { system.add_edge(i, j, 0.0, 1.0); });
  state.analyse(system.matrix());
}

TemperatureFieldResult TemperatureFieldSolver::recover(const DisplacementField& displacement) {
  const auto start = std::chrono::steady_clock::now();
  const GridLayout layout = grid_layout(displacement);
  std::lock_guard lock(state_->mutex);
  State& state = *state_;
  state.use_grid(displacement, layout, options_);
  const std::vector<std::uint8_t> measured = measured_nodes(displacement, options_);
  const NodeSigmas sigmas = node_sigmas(displacement, measured);
  const bool weighted = options_.weight_by_sigma && sigmas.any();
  const std::vector<double> weights =
      edge_weights(displacement.rows, displacement.cols, measured, weighted ? &sigmas : nullptr, options_.fill_weight);
  const bool same_nodes = measured == state.factorised_for;
  const bool same_weights = same_nodes && weights == state.factorised_weights;

  const double target_per_px = geometry_.gradient_per_m(1.0) * layout.step_px / geometry_.px_per_m_flow();
  EdgeSystem system(state.unknown, state.unknowns, !same_weights);
  // Trapezoid target along an edge from the displacement component along it;
  // a weak zero target (harmonic fill) when either end is not a measurement.
  std::size_t edge = 0;
  auto add_edge = [&](std::size_t i, std::size_t j, bool along_x) {
    const double weight = weights[edge++];
    if (!measured[i] || !measured[j]) return system.add_edge(i, j, 0.0, weight);
    const DisplacementVector &a = displacement.vectors[i], &b = displacement.vectors[j];
    const double mean_shift_px = along_x ? 0.5 * (a.u_px + b.u_px) : 0.5 * (a.v_px + b.v_px);
    system.add_edge(i, j, target_per_px * mean_shift_px, weight);
  };
  for_each_edge(displacement.rows, displacement.cols, add_edge);
  // The σ estimate solves with the factor itself, so it needs the frame's own.
  const bool may_iterate = same_nodes && !options_.estimate_uncertainty && options_.iterative_tolerance > 0;
  const FrameSolution solution =
      same_weights ? FrameSolution{state.factorisation->solve(system.rhs()), 0, 0, 1}
                   : state.solve_new_weights(system.matrix(), system.rhs(), measured, weights, may_iterate,
                                             options_.iterative_tolerance);
  TemperatureFieldResult result =
      field_from_solution(displacement, layout, geometry_, state.unknown, measured, solution.delta_n);
  result.summary.weighted = weighted;
  result.summary.median_sigma_nodes = sigmas.median_filled;
  result.summary.solver_iterations = solution.iterations;
  result.summary.relative_residual = solution.relative_residual;
  result.summary.kept_factor_condition = solution.condition_bound;
  if (options_.estimate_uncertainty && sigmas.any()) {
    const auto sampling_start = std::chrono::steady_clock::now();
    const Eigen::VectorXd variance =
        propagated_variance(*state.factorisation, state.unknown, state.unknowns, displacement, measured, weights,
                            sigmas, target_per_px, options_.uncertainty_samples, options_.uncertainty_seed);
    set_uncertainty(result.field, state.unknown, variance);
    result.summary.uncertainty_estimated = true;
    result.summary.uncertainty_samples = options_.uncertainty_samples;
    result.summary.uncertainty_seconds = seconds_since(sampling_start);
  }
  result.summary.seconds = seconds_since(start);
  ++state.fields;
  return result;
}

TemperatureFieldResult recover_temperature_field(const DisplacementField& displacement, const BosGeometry& geometry,
                                                 const TemperatureFieldOptions& options) {
  TemperatureFieldSolver solver(geometry, options);
  solver.state_->one_shot = true;
  return solver.recover(displacement);
}

namespace {

// c of average_sigma_c: the averaging weights times |dT/dn| at each node, on
// the unknowns (an ambient border node's δn is fixed, so it adds nothing);
// nullopt where a node of the average has no σ to give.
std::optional<Eigen::VectorXd> averaging_vector(const TemperatureField& field, const std::vector<int>& unknown,
                                                int unknowns, const std::vector<std::size_t>& nodes,
                                                const std::vector<double>& weights) {
  if (nodes.size() != weights.size()) throw std::invalid_argument("average_sigma_c: a weight per node");
  Eigen::VectorXd c = Eigen::VectorXd::Zero(unknowns);
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const std::size_t i = nodes[k];
    if (i >= field.temperature_c.size() || i >= unknown.size()) {
      throw std::invalid_argument("average_sigma_c: a node off the grid");
    }
    if (weights[k] == 0) continue;
    if (!field.measured[i] || !field.physical[i]) return std::nullopt;
    if (unknown[i] < 0) continue;
    c[unknown[i]] += weights[k] * (field.temperature_c[i] + kZeroCelsiusK) / (field.refractive_index[i] - 1);
  }
  return c;
}

// Σ_k σ_k² y_k², y = Bᵀ z: the derivative of zᵀ·rhs with respect to each
// measured node's u and v, the right-hand side assembled as recover()'s.
double noise_variance_along(const Eigen::VectorXd& z, const std::vector<int>& unknown, int rows, int cols,
                            const std::vector<std::uint8_t>& measured, const std::vector<double>& weights,
                            const NodeSigmas& sigmas, double target_per_px) {
  std::vector<double> du(measured.size(), 0.0), dv(measured.size(), 0.0);
  std::size_t edge = 0;
  for_each_edge(rows, cols, [&](std::size_t i, std::size_t j, bool along_x) {
    const double w = weights[edge++];
    if (!measured[i] || !measured[j]) return;
    const double zi = unknown[i] >= 0 ? z[unknown[i]] : 0.0, zj = unknown[j] >= 0 ? z[unknown[j]] : 0.0;
    const double d = w * target_per_px * 0.5 * (zj - zi);  // each end's share of the trapezoid target
    std::vector<double>& component = along_x ? du : dv;
    component[i] += d;
    component[j] += d;
  });
  double variance = 0;
  for (std::size_t k = 0; k < measured.size(); ++k) {
    if (!measured[k]) continue;
    variance += sigmas.u[k] * sigmas.u[k] * du[k] * du[k] + sigmas.v[k] * sigmas.v[k] * dv[k] * dv[k];
  }
  return variance;
}

}  // namespace

std::optional<double> TemperatureFieldSolver::average_sigma_c(const DisplacementField& displacement,
                                                              const TemperatureField& field,
                                                              const std::vector<std::size_t>& nodes,
                                                              const std::vector<double>& weights) {
  const GridLayout layout = grid_layout(displacement);
  if (field.temperature_c.size() != displacement.size()) {
    throw std::invalid_argument("average_sigma_c: the temperature field is not the displacement field's");
  }
  std::lock_guard lock(state_->mutex);
  State& state = *state_;
  state.use_grid(displacement, layout, options_);
  std::vector<std::uint8_t> measured = measured_nodes(displacement, options_);
  const NodeSigmas sigmas = node_sigmas(displacement, measured);
  if (!sigmas.any()) return std::nullopt;
  const auto c = averaging_vector(field, state.unknown, state.unknowns, nodes, weights);
  if (!c) return std::nullopt;
  const bool weighted = options_.weight_by_sigma;
  std::vector<double> edge_weight =
      edge_weights(displacement.rows, displacement.cols, measured, weighted ? &sigmas : nullptr, options_.fill_weight);
  // A's inverse times c: with the kept factor when it is this matrix's, by
  // conjugate gradients on it when only σ moved (exact to the tolerance, as
  // the frame's own solve), else factorised anew.
  Eigen::VectorXd z;
  if (measured == state.factorised_for && edge_weight == state.factorised_weights) {
    z = state.factorisation->solve(*c);
  } else {
    EdgeSystem system(state.unknown, state.unknowns, true);
    std::size_t edge = 0;
    for_each_edge(displacement.rows, displacement.cols,
                  [&](std::size_t i, std::size_t j, bool) { system.add_edge(i, j, 0.0, edge_weight[edge++]); });
    const bool may_iterate = measured == state.factorised_for && state.analysed && options_.iterative_tolerance > 0;
    z = state.solve_new_weights(system.matrix(), *c, measured, edge_weight, may_iterate, options_.iterative_tolerance)
            .delta_n;
  }
  const double target_per_px = geometry_.gradient_per_m(1.0) * layout.step_px / geometry_.px_per_m_flow();
  const double variance = noise_variance_along(z, state.unknown, displacement.rows, displacement.cols, measured,
                                               edge_weight, sigmas, target_per_px);
  return std::sqrt(std::max(variance, 0.0));
}

}  // namespace bosfuse::fusion
