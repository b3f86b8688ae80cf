#pragma once
// Thermocouple maths on ITS-90: the NIST reference functions (NIST Monograph
// 175 / NIST SRD 60) that turn a temperature into the EMF a letter-type
// thermocouple (B, E, J, K, N, R, S, T) produces with its reference junction
// at 0 °C, and back. Use it for devices or Modbus channels that deliver
// millivolts instead of temperatures: compensated_temperature_c() takes the
// measured EMF and the cold-junction temperature and does the compensation
// in voltage, which is the only correct way (EMFs add; temperatures do not).
//
// Every conversion returns a status with its value: an input outside a type's
// range is kOutOfRange and a NaN or infinite input is kInvalidValue, and in
// both cases there is no value. Temperatures are °C, EMFs millivolts.
//
// EMF → temperature: NIST's inverse polynomials (stated accuracy ±0.0002 to
// ±0.06 °C depending on type and subrange) give the first estimate, then a
// safeguarded Newton iteration on the reference function makes the result
// its exact inverse (round trips agree to better than 1e-6 °C). Because the
// reference function, not the inverse polynomial, decides, EMFs are served
// over emf_to_temperature_range(): the reference function's whole range,
// which for E, K, N and T reaches below NIST's inverse range (e.g. K: down to
// −270 °C instead of −200 °C; sensitivity there is only about 1 µV/°C).
// Type B keeps NIST's inverse range, 250…1820 °C: below about 21 °C its EMF
// is not monotonic, and below 250 °C it is too small to be useful.
// nist_inverse_temperature_c() exposes the bare NIST polynomial.

#include <optional>
#include <string_view>

#include "storage/records.h"

namespace bosfuse::acquisition {

enum class ThermocoupleType { kB, kE, kJ, kK, kN, kR, kS, kT };

// "K" or "k" (surrounding spaces ignored); nullopt for anything else.
std::optional<ThermocoupleType> parse_thermocouple_type(std::string_view text);
std::string_view to_string(ThermocoupleType type);  // "K"

struct TemperatureRange {
  double low_c;
  double high_c;
};

// Where the reference function E(t) is defined (e.g. K: −270…1372 °C).
TemperatureRange reference_function_range(ThermocoupleType type);
// The temperatures EMF → temperature serves (see the top of this file).
TemperatureRange emf_to_temperature_range(ThermocoupleType type);
// The range NIST's inverse polynomials cover (e.g. K: −200…1372 °C).
TemperatureRange nist_inverse_range(ThermocoupleType type);

// A value only when status is kOk.
struct EmfResult {
  storage::SampleStatus status = storage::SampleStatus::kOk;
  std::optional<double> emf_mv;
  bool ok() const { return status == storage::SampleStatus::kOk; }
};

struct TemperatureResult {
  storage::SampleStatus status = storage::SampleStatus::kOk;
  std::optional<double> temperature_c;
  bool ok() const { return status == storage::SampleStatus::kOk; }
};

// The reference function: EMF with the reference junction at 0 °C.
EmfResult emf_mv_at(ThermocoupleType type, double temperature_c);

// The temperature whose reference EMF is emf_mv (reference junction at 0 °C).
TemperatureResult temperature_c_at(ThermocoupleType type, double emf_mv);

// NIST's inverse polynomial alone, over nist_inverse_range(): no refinement,
// so it carries NIST's stated error. For diagnostics and comparisons.
TemperatureResult nist_inverse_temperature_c(ThermocoupleType type, double emf_mv);

// The hot-junction temperature of a thermocouple whose cold junction (the
// terminals at the instrument) is at cold_junction_c and which produces
// measured_emf_mv there: E = measured_emf_mv + E(cold_junction_c), inverted.
// A cold junction outside the type's range is kOutOfRange like any input.
TemperatureResult compensated_temperature_c(ThermocoupleType type, double measured_emf_mv, double cold_junction_c);

}  // namespace bosfuse::acquisition
