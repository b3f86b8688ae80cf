#pragma once
// The NIST ITS-90 coefficient tables behind thermocouple.h: for each letter
// type, the reference function E(t) as polynomials over temperature
// subranges (plus type K's exponential term), and NIST's approximate inverse
// polynomials t(E) over their stated subranges with their stated error
// bounds. Units are NIST's: °C and mV. Source: NIST Monograph 175 / NIST SRD
// 60 (srdata.nist.gov/its90, allcoeff.tab). Most callers want thermocouple.h;
// this is here so tests and diagnostics can reach the published pieces.

#include <optional>
#include <span>

#include "acquisition/thermocouple.h"

namespace bosfuse::acquisition::its90 {

// Type K adds a0 · exp(a1 · (t − a2)²) to its subrange above 0 °C.
struct ExponentialTerm {
  double a0;
  double a1;
  double a2;
};

// E(t) = sum c_i t^i (+ the exponential term, if any) over [low_c, high_c].
struct ForwardPolynomial {
  double low_c;
  double high_c;
  std::span<const double> coefficients;  // c_0 first
  std::optional<ExponentialTerm> exponential = std::nullopt;
};

// t(E) = sum d_i E^i over [low_mv, high_mv]; NIST states that it reproduces
// the reference function to within [error_low_c, error_high_c].
struct InversePolynomial {
  double low_c;
  double high_c;
  double low_mv;
  double high_mv;
  double error_low_c;
  double error_high_c;
  std::span<const double> coefficients;  // d_0 first
};

struct TypeCoefficients {
  std::span<const ForwardPolynomial> forward;  // ascending, adjacent
  std::span<const InversePolynomial> inverse;  // ascending by low_mv; R and S overlap
};

const TypeCoefficients& coefficients(ThermocoupleType type);

}  // namespace bosfuse::acquisition::its90
