#include "acquisition/thermocouple.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <span>

#include "acquisition/thermocouple_coefficients.h"

namespace bosfuse::acquisition {
namespace {

using its90::ForwardPolynomial;
using its90::InversePolynomial;
using storage::SampleStatus;

constexpr std::array<std::string_view, 8> kTypeNames = {"B", "E", "J", "K", "N", "R", "S", "T"};

// Newton stops once a step is this small; the reference function is then
// inverted far below any thermocouple's real uncertainty.
constexpr double kNewtonToleranceC = 1e-9;
constexpr int kMaxNewtonSteps = 100;
// An EMF this far beyond a range end counts as the end: cold-junction
// compensation adds two EMFs, and the sum of E(end) − E(t_cj) and E(t_cj)
// must not fall out of range by a rounding error. 1 nV is far below any
// instrument's resolution.
constexpr double kEmfRoundingToleranceMv = 1e-6 * 1e-3;

double horner(std::span<const double> coefficients, double x) {
  double sum = 0.0;
  for (auto it = coefficients.rbegin(); it != coefficients.rend(); ++it) sum = sum * x + *it;
  return sum;
}

double horner_derivative(std::span<const double> coefficients, double x) {
  double sum = 0.0;
  for (std::size_t i = coefficients.size() - 1; i >= 1; --i) sum = sum * x + static_cast<double>(i) * coefficients[i];
  return sum;
}

// The subrange holding t; t must lie inside the type's range. At a shared
// boundary the lower subrange answers: NIST's pieces agree there.
const ForwardPolynomial& forward_piece(ThermocoupleType type, double temperature_c) {
  const auto pieces = its90::coefficients(type).forward;
  for (const auto& piece : pieces) {
    if (temperature_c <= piece.high_c) return piece;
  }
  return pieces.back();
}

double reference_emf_mv(ThermocoupleType type, double temperature_c) {
  const auto& piece = forward_piece(type, temperature_c);
  double emf_mv = horner(piece.coefficients, temperature_c);
  if (piece.exponential) {
    const auto& x = *piece.exponential;
    emf_mv += x.a0 * std::exp(x.a1 * (temperature_c - x.a2) * (temperature_c - x.a2));
  }
  return emf_mv;
}

double reference_seebeck_mv_per_c(ThermocoupleType type, double temperature_c) {
  const auto& piece = forward_piece(type, temperature_c);
  double slope = horner_derivative(piece.coefficients, temperature_c);
  if (piece.exponential) {
    const auto& x = *piece.exponential;
    const double offset = temperature_c - x.a2;
    slope += x.a0 * std::exp(x.a1 * offset * offset) * 2.0 * x.a1 * offset;
  }
  return slope;
}

bool inside(TemperatureRange range, double temperature_c) {
  return temperature_c >= range.low_c && temperature_c <= range.high_c;
}

// Where the EMF lies inside several of NIST's subranges (R and S overlap
// around the gold point), the later one is the more accurate.
const InversePolynomial* inverse_piece(ThermocoupleType type, double emf_mv) {
  const InversePolynomial* found = nullptr;
  for (const auto& piece : its90::coefficients(type).inverse) {
    if (emf_mv >= piece.low_mv && emf_mv <= piece.high_mv) found = &piece;
  }
  return found;
}

// NIST's polynomial for the nearest subrange: the starting point for Newton,
// also for EMFs beyond NIST's inverse range (clamped to its end).
double first_estimate_c(ThermocoupleType type, double emf_mv) {
  const auto pieces = its90::coefficients(type).inverse;
  if (emf_mv < pieces.front().low_mv) return pieces.front().low_c;
  if (emf_mv > pieces.back().high_mv) return pieces.back().high_c;
  return horner(inverse_piece(type, emf_mv)->coefficients, emf_mv);
}

// Safeguarded Newton: E is strictly increasing over `range`, so [low, high]
// always brackets the root and a step that leaves it becomes a bisection.
double invert_reference_function(ThermocoupleType type, double emf_mv, TemperatureRange range) {
  double low_c = range.low_c;
  double high_c = range.high_c;
  double t = std::clamp(first_estimate_c(type, emf_mv), low_c, high_c);
  for (int step = 0; step < kMaxNewtonSteps; ++step) {
    const double residual_mv = reference_emf_mv(type, t) - emf_mv;
    if (residual_mv == 0.0) break;
    if (residual_mv < 0.0) {
      low_c = t;
    } else {
      high_c = t;
    }
    double next = t - residual_mv / reference_seebeck_mv_per_c(type, t);
    if (!(next > low_c && next < high_c)) next = 0.5 * (low_c + high_c);
    const bool converged = std::abs(next - t) < kNewtonToleranceC;
    t = next;
    if (converged || high_c - low_c < kNewtonToleranceC) break;
  }
  return t;
}

TemperatureResult temperature_result(SampleStatus status) { return TemperatureResult{status, std::nullopt}; }

}  // namespace

std::optional<ThermocoupleType> parse_thermocouple_type(std::string_view text) {
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front()))) text.remove_prefix(1);
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.remove_suffix(1);
  if (text.size() != 1) return std::nullopt;
  const char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(text.front())));
  for (std::size_t i = 0; i < kTypeNames.size(); ++i) {
    if (kTypeNames[i].front() == letter) return static_cast<ThermocoupleType>(i);
  }
  return std::nullopt;
}

std::string_view to_string(ThermocoupleType type) { return kTypeNames[static_cast<std::size_t>(type)]; }

TemperatureRange reference_function_range(ThermocoupleType type) {
  const auto pieces = its90::coefficients(type).forward;
  return {pieces.front().low_c, pieces.back().high_c};
}

TemperatureRange nist_inverse_range(ThermocoupleType type) {
  const auto pieces = its90::coefficients(type).inverse;
  return {pieces.front().low_c, pieces.back().high_c};
}

TemperatureRange emf_to_temperature_range(ThermocoupleType type) {
  // B's EMF is not monotonic below about 21 °C and tiny up to 250 °C, so it
  // keeps NIST's inverse range; every other type's reference function is
  // strictly increasing over its whole range and can be inverted there.
  if (type == ThermocoupleType::kB) return nist_inverse_range(type);
  return reference_function_range(type);
}

EmfResult emf_mv_at(ThermocoupleType type, double temperature_c) {
  if (!std::isfinite(temperature_c)) return {SampleStatus::kInvalidValue, std::nullopt};
  if (!inside(reference_function_range(type), temperature_c)) return {SampleStatus::kOutOfRange, std::nullopt};
  return {SampleStatus::kOk, reference_emf_mv(type, temperature_c)};
}

TemperatureResult temperature_c_at(ThermocoupleType type, double emf_mv) {
  if (!std::isfinite(emf_mv)) return temperature_result(SampleStatus::kInvalidValue);
  const TemperatureRange range = emf_to_temperature_range(type);
  const double low_mv = reference_emf_mv(type, range.low_c);
  const double high_mv = reference_emf_mv(type, range.high_c);
  if (emf_mv < low_mv - kEmfRoundingToleranceMv || emf_mv > high_mv + kEmfRoundingToleranceMv) {
    return temperature_result(SampleStatus::kOutOfRange);
  }
  return {SampleStatus::kOk, invert_reference_function(type, std::clamp(emf_mv, low_mv, high_mv), range)};
}

TemperatureResult nist_inverse_temperature_c(ThermocoupleType type, double emf_mv) {
  if (!std::isfinite(emf_mv)) return temperature_result(SampleStatus::kInvalidValue);
  const InversePolynomial* piece = inverse_piece(type, emf_mv);
  if (piece == nullptr) return temperature_result(SampleStatus::kOutOfRange);
  return {SampleStatus::kOk, horner(piece->coefficients, emf_mv)};
}

TemperatureResult compensated_temperature_c(ThermocoupleType type, double measured_emf_mv, double cold_junction_c) {
  if (!std::isfinite(measured_emf_mv)) return temperature_result(SampleStatus::kInvalidValue);
  const EmfResult cold_junction = emf_mv_at(type, cold_junction_c);
  if (!cold_junction.ok()) return temperature_result(cold_junction.status);
  return temperature_c_at(type, measured_emf_mv + *cold_junction.emf_mv);
}

}  // namespace bosfuse::acquisition
