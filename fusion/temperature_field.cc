#include "fusion/temperature_field.h"

#include <fmt/format.h>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "fusion/field_csv.h"

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

// The least-squares system for δn at interior nodes: each edge i→j asks
// δn_j − δn_i = target, border nodes are fixed at δn = 0 (ambient).
class EdgeSystem {
 public:
  EdgeSystem(std::vector<int> unknown_index, int unknowns)
      : unknown_(std::move(unknown_index)), rhs_(Eigen::VectorXd::Zero(unknowns)), unknowns_(unknowns) {}

  void add_edge(std::size_t i, std::size_t j, double target, double weight) {
    const int ui = unknown_[i], uj = unknown_[j];
    if (ui >= 0) {
      triplets_.emplace_back(ui, ui, weight);
      rhs_[ui] -= weight * target;
    }
    if (uj >= 0) {
      triplets_.emplace_back(uj, uj, weight);
      rhs_[uj] += weight * target;
    }
    if (ui >= 0 && uj >= 0) {
      triplets_.emplace_back(ui, uj, -weight);
      triplets_.emplace_back(uj, ui, -weight);
    }
  }

  Eigen::VectorXd solve() const {
    Eigen::SparseMatrix<double> a(unknowns_, unknowns_);
    a.setFromTriplets(triplets_.begin(), triplets_.end());
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(a);
    if (solver.info() != Eigen::Success) throw std::runtime_error("temperature field: Poisson matrix not factorised");
    Eigen::VectorXd x = solver.solve(rhs_);
    if (solver.info() != Eigen::Success) throw std::runtime_error("temperature field: Poisson solve failed");
    return x;
  }

 private:
  std::vector<int> unknown_;
  std::vector<Eigen::Triplet<double>> triplets_;
  Eigen::VectorXd rhs_;
  int unknowns_;
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

std::string TemperatureFieldOptions::Validate() const {
  if (max_nodes < 9) return "max_nodes must be at least 9";
  if (!(fill_weight > 0 && fill_weight <= 1)) return "fill_weight must lie in (0, 1]";
  if (open_top && open_bottom && open_left && open_right) return "at least one image edge must be ambient air";
  return {};
}

std::optional<double> TemperatureField::temperature_at(double x_px, double y_px) const {
  const double fx = (x_px - x0_px) / step_px, fy = (y_px - y0_px) / step_px;
  if (!(fx >= 0 && fy >= 0 && fx <= cols - 1 && fy <= rows - 1)) return std::nullopt;
  const int c0 = std::min(static_cast<int>(fx), cols - 2), r0 = std::min(static_cast<int>(fy), rows - 2);
  const double ax = fx - c0, ay = fy - r0;
  const double t00 = temperature_c[index(r0, c0)], t01 = temperature_c[index(r0, c0 + 1)];
  const double t10 = temperature_c[index(r0 + 1, c0)], t11 = temperature_c[index(r0 + 1, c0 + 1)];
  const double value = (1 - ay) * ((1 - ax) * t00 + ax * t01) + ay * ((1 - ax) * t10 + ax * t11);
  if (!std::isfinite(value)) return std::nullopt;
  return value;
}

std::string TemperatureFieldSummary::brief_report() const {
  return fmt::format(
      "temperature field: {} nodes ({} on the ambient border, {} unmeasured filled, {} unphysical), {:.2f} .. {:.2f} "
      "degC, {:.3f} s",
      nodes, boundary_nodes, unmeasured_nodes, unphysical_nodes, min_c, max_c, seconds);
}

TemperatureFieldResult recover_temperature_field(const DisplacementField& displacement, const BosGeometry& geometry,
                                                 const TemperatureFieldOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (const auto problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  const GridLayout layout = grid_layout(displacement);
  if (displacement.size() > static_cast<std::size_t>(options.max_nodes)) {
    throw std::invalid_argument(
        fmt::format("temperature field: {} nodes exceed max_nodes {}", displacement.size(), options.max_nodes));
  }
  const int rows = displacement.rows, cols = displacement.cols;
  std::vector<int> unknown(displacement.size(), -1);
  int unknowns = 0;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      if (!on_ambient_border(displacement, r, c, options)) unknown[static_cast<std::size_t>(r) * cols + c] = unknowns++;
    }
  }
  const double step_m = layout.step_px / geometry.px_per_m_flow();
  EdgeSystem system(unknown, unknowns);
  // Trapezoid target along an edge from the displacement component along it;
  // a weak zero target (harmonic fill) when either end is not a measurement.
  auto add_edge = [&](std::size_t i, std::size_t j, bool along_x) {
    const DisplacementVector &a = displacement.vectors[i], &b = displacement.vectors[j];
    if (!is_measured(a, options) || !is_measured(b, options)) return system.add_edge(i, j, 0.0, options.fill_weight);
    const double mean_shift_px = along_x ? 0.5 * (a.u_px + b.u_px) : 0.5 * (a.v_px + b.v_px);
    system.add_edge(i, j, geometry.gradient_per_m(mean_shift_px) * step_m, 1.0);
  };
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * cols + c;
      if (c + 1 < cols) add_edge(i, i + 1, true);
      if (r + 1 < rows) add_edge(i, i + cols, false);
    }
  }
  const Eigen::VectorXd delta_n = system.solve();

  TemperatureFieldResult result;
  TemperatureField& field = result.field;
  field.rows = rows;
  field.cols = cols;
  field.x0_px = layout.x0_px;
  field.y0_px = layout.y0_px;
  field.step_px = layout.step_px;
  field.temperature_c.resize(displacement.size());
  field.refractive_index.resize(displacement.size());
  field.measured.resize(displacement.size());
  field.physical.resize(displacement.size());
  auto& summary = result.summary;
  summary.nodes = displacement.size();
  summary.unknowns = static_cast<std::size_t>(unknowns);
  summary.boundary_nodes = displacement.size() - summary.unknowns;
  summary.min_c = std::numeric_limits<double>::infinity();
  summary.max_c = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < displacement.size(); ++i) {
    const double n = geometry.ambient_refractive_index() + (unknown[i] >= 0 ? delta_n[unknown[i]] : 0.0);
    const double t = geometry.temperature_c(n);
    field.refractive_index[i] = n;
    field.temperature_c[i] = t;
    field.measured[i] = is_measured(displacement.vectors[i], options) ? 1 : 0;
    field.physical[i] = std::isfinite(t) ? 1 : 0;
    summary.unmeasured_nodes += field.measured[i] ? 0 : 1;
    summary.unphysical_nodes += field.physical[i] ? 0 : 1;
    if (std::isfinite(t)) {
      summary.min_c = std::min(summary.min_c, t);
      summary.max_c = std::max(summary.max_c, t);
    }
  }
  if (summary.unphysical_nodes == summary.nodes) summary.min_c = summary.max_c = std::nan("");
  summary.seconds = seconds_since(start);
  return result;
}

void write_csv(const TemperatureField& field, const std::filesystem::path& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path.string() + ": cannot open for writing");
  out << field_csv_header(kTemperatureColumns) << "\n";
  for (int r = 0; r < field.rows; ++r) {
    for (int c = 0; c < field.cols; ++c) {
      const std::size_t i = field.index(r, c);
      const double t = field.temperature_c[i];
      out << fmt::format("{:.1f},{:.1f},{},{}\n", field.x0_px + c * field.step_px, field.y0_px + r * field.step_px,
                         std::isfinite(t) ? fmt::format("{:.4f}", t) : std::string(), int{field.measured[i]});
    }
  }
  if (!out.flush()) throw std::runtime_error(path.string() + ": write failed");
}

}  // namespace bosfuse::fusion
