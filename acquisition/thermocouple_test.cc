#include "acquisition/thermocouple.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "acquisition/thermocouple_coefficients.h"

namespace bosfuse::acquisition {
namespace {

using storage::SampleStatus;
using Type = ThermocoupleType;

constexpr Type kAllTypes[] = {Type::kB, Type::kE, Type::kJ, Type::kK, Type::kN, Type::kR, Type::kS, Type::kT};

// NIST prints EMFs to 0.001 mV, so a printed entry is exact to half of that.
constexpr double kTablePrecisionMv = 0.0005;

double emf(Type type, double temperature_c) {
  const EmfResult result = emf_mv_at(type, temperature_c);
  EXPECT_TRUE(result.ok()) << to_string(type) << " at " << temperature_c << " °C";
  return result.emf_mv.value_or(std::numeric_limits<double>::quiet_NaN());
}

double temperature(Type type, double emf_mv) {
  const TemperatureResult result = temperature_c_at(type, emf_mv);
  EXPECT_TRUE(result.ok()) << to_string(type) << " at " << emf_mv << " mV";
  return result.temperature_c.value_or(std::numeric_limits<double>::quiet_NaN());
}

double seebeck_mv_per_c(Type type, double temperature_c) {
  const TemperatureRange range = reference_function_range(type);
  const double low = std::max(range.low_c, temperature_c - 0.01);
  const double high = std::min(range.high_c, temperature_c + 0.01);
  return (emf(type, high) - emf(type, low)) / (high - low);
}

// ------------------------------------------------------------ NIST tables

// Entries of the NIST ITS-90 thermocouple tables (NIST Monograph 175, the
// per-type tables "Thermoelectric voltage as a function of temperature,
// reference junctions at 0 °C", also NIST SRD 60), printed in mV to three
// decimals. Each type has entries in every subrange of its reference function
// and at both ends of its range.
struct TableEntry {
  Type type;
  double temperature_c;
  double emf_mv;
};

const TableEntry kNistTableEntries[] = {
    // Type B table
    {Type::kB, 100.0, 0.033},
    {Type::kB, 250.0, 0.291},
    {Type::kB, 500.0, 1.242},
    {Type::kB, 700.0, 2.431},
    {Type::kB, 1000.0, 4.834},
    {Type::kB, 1500.0, 10.099},
    {Type::kB, 1820.0, 13.820},
    // Type E table
    {Type::kE, -270.0, -9.835},
    {Type::kE, -200.0, -8.825},
    {Type::kE, -100.0, -5.237},
    {Type::kE, 100.0, 6.319},
    {Type::kE, 1000.0, 76.373},
    // Type J table
    {Type::kJ, -210.0, -8.095},
    {Type::kJ, -100.0, -4.633},
    {Type::kJ, 100.0, 5.269},
    {Type::kJ, 500.0, 27.393},
    {Type::kJ, 760.0, 42.919},
    {Type::kJ, 1000.0, 57.953},
    {Type::kJ, 1200.0, 69.553},
    // Type K table
    {Type::kK, -270.0, -6.458},
    {Type::kK, -200.0, -5.891},
    {Type::kK, -100.0, -3.554},
    {Type::kK, 0.0, 0.000},
    {Type::kK, 25.0, 1.000},
    {Type::kK, 100.0, 4.096},
    {Type::kK, 200.0, 8.138},
    {Type::kK, 300.0, 12.209},
    {Type::kK, 400.0, 16.397},
    {Type::kK, 500.0, 20.644},
    {Type::kK, 600.0, 24.905},
    {Type::kK, 800.0, 33.275},
    {Type::kK, 1000.0, 41.276},
    {Type::kK, 1200.0, 48.838},
    {Type::kK, 1372.0, 54.886},
    // Type N table
    {Type::kN, -270.0, -4.345},
    {Type::kN, -200.0, -3.990},
    {Type::kN, 100.0, 2.774},
    {Type::kN, 600.0, 20.613},
    {Type::kN, 1000.0, 36.256},
    {Type::kN, 1300.0, 47.513},
    // Type R table
    {Type::kR, -50.0, -0.226},
    {Type::kR, 100.0, 0.647},
    {Type::kR, 250.0, 1.923},
    {Type::kR, 1000.0, 10.506},
    {Type::kR, 1200.0, 13.228},
    {Type::kR, 1500.0, 17.451},
    {Type::kR, 1768.0, 21.101},
    // Type S table
    {Type::kS, -50.0, -0.236},
    {Type::kS, 100.0, 0.646},
    {Type::kS, 250.0, 1.874},
    {Type::kS, 1000.0, 9.587},
    {Type::kS, 1200.0, 11.951},
    {Type::kS, 1500.0, 15.582},
    // Type T table
    {Type::kT, -270.0, -6.258},
    {Type::kT, -200.0, -5.603},
    {Type::kT, -100.0, -3.379},
    {Type::kT, 100.0, 4.279},
    {Type::kT, 200.0, 9.288},
    {Type::kT, 400.0, 20.872},
};

TEST(ThermocoupleNistTable, ReferenceFunctionsReproducePrintedEntries) {
  for (const auto& entry : kNistTableEntries) {
    EXPECT_NEAR(emf(entry.type, entry.temperature_c), entry.emf_mv, kTablePrecisionMv)
        << "type " << to_string(entry.type) << " table, " << entry.temperature_c << " °C";
  }
}

// Going back from a printed EMF, the only error is the table's rounding,
// seen through the thermocouple's sensitivity. Entries at the ends of the
// range are left out: rounding may put them just outside it, and an EMF
// outside the range is rejected (RangeEndsInvertToThemselves covers the ends).
TEST(ThermocoupleNistTable, PrintedEntriesInvertToTheirTemperatures) {
  for (const auto& entry : kNistTableEntries) {
    const TemperatureRange served = emf_to_temperature_range(entry.type);
    if (entry.temperature_c <= served.low_c || entry.temperature_c >= served.high_c) continue;
    const double rounding_c = kTablePrecisionMv / seebeck_mv_per_c(entry.type, entry.temperature_c);
    EXPECT_NEAR(temperature(entry.type, entry.emf_mv), entry.temperature_c, rounding_c + 1e-9)
        << "type " << to_string(entry.type) << " table, " << entry.temperature_c << " °C";
  }
}

// ------------------------------------------------- NIST inverse functions

double evaluate(std::span<const double> coefficients, double x) {
  double sum = 0.0;
  for (std::size_t i = coefficients.size(); i-- > 0;) sum = sum * x + coefficients[i];
  return sum;
}

// NIST states each inverse polynomial's error (t_inverse − t_reference) as a
// range rounded to one significant digit; the extremes of our sweep exceed
// the rounded bounds by up to a tenth of the larger one (e.g. J below 0 °C:
// +0.033 against a stated +0.03), so that much is allowed.
double rounding_allowance_c(const its90::InversePolynomial& piece) {
  return 0.1 * std::max(std::abs(piece.error_low_c), std::abs(piece.error_high_c)) + 1e-4;
}

TEST(ThermocoupleNistInverse, EachSubrangeIsWithinNistStatedError) {
  for (Type type : kAllTypes) {
    for (const auto& piece : its90::coefficients(type).inverse) {
      const double allowance = rounding_allowance_c(piece);
      double worst_low = 0.0;
      double worst_high = 0.0;
      constexpr int kSteps = 2000;
      for (int i = 0; i <= kSteps; ++i) {
        const double t = std::lerp(piece.low_c, piece.high_c, static_cast<double>(i) / kSteps);
        const double error_c = evaluate(piece.coefficients, emf(type, t)) - t;
        worst_low = std::min(worst_low, error_c);
        worst_high = std::max(worst_high, error_c);
      }
      EXPECT_GE(worst_low, piece.error_low_c - allowance) << to_string(type) << " from " << piece.low_c << " °C";
      EXPECT_LE(worst_high, piece.error_high_c + allowance) << to_string(type) << " from " << piece.low_c << " °C";
    }
  }
}

TEST(ThermocoupleNistInverse, PublicFunctionUsesTheInverseOverItsStatedRange) {
  // K, 500 °C: the printed 20.644 mV is where NIST's second and third
  // subranges meet; both put it within 0.06 °C of 500 °C.
  EXPECT_NEAR(*nist_inverse_temperature_c(Type::kK, 20.644).temperature_c, 500.0, 0.06);
  EXPECT_NEAR(*nist_inverse_temperature_c(Type::kK, 4.096).temperature_c, 100.0, 0.06);
  EXPECT_NEAR(*nist_inverse_temperature_c(Type::kS, 9.587).temperature_c, 1000.0, 0.02);
  // Outside NIST's stated inverse range there is no value, even where the
  // refined inverse serves one.
  EXPECT_EQ(nist_inverse_temperature_c(Type::kK, -6.0).status, SampleStatus::kOutOfRange);
  EXPECT_TRUE(temperature_c_at(Type::kK, -6.0).ok());
  EXPECT_EQ(nist_inverse_temperature_c(Type::kK, 54.9).status, SampleStatus::kOutOfRange);
  EXPECT_EQ(nist_inverse_temperature_c(Type::kB, 0.2).status, SampleStatus::kOutOfRange);
  EXPECT_EQ(nist_inverse_temperature_c(Type::kK, std::nan("")).status, SampleStatus::kInvalidValue);
}

// ------------------------------------------------------------ round trips

TEST(ThermocoupleRoundTrip, TemperatureToEmfToTemperatureIsExactOverEveryTypesRange) {
  for (Type type : kAllTypes) {
    const TemperatureRange range = emf_to_temperature_range(type);
    double worst_c = 0.0;
    constexpr int kSteps = 20000;
    for (int i = 0; i <= kSteps; ++i) {
      const double t = std::lerp(range.low_c, range.high_c, static_cast<double>(i) / kSteps);
      worst_c = std::max(worst_c, std::abs(temperature(type, emf(type, t)) - t));
    }
    EXPECT_LT(worst_c, 1e-6) << "type " << to_string(type);
  }
}

TEST(ThermocoupleRoundTrip, EmfToTemperatureToEmfIsExactOverEveryTypesRange) {
  for (Type type : kAllTypes) {
    const TemperatureRange range = emf_to_temperature_range(type);
    const double low_mv = emf(type, range.low_c);
    const double high_mv = emf(type, range.high_c);
    constexpr int kSteps = 5000;
    for (int i = 0; i <= kSteps; ++i) {
      const double e = std::lerp(low_mv, high_mv, static_cast<double>(i) / kSteps);
      ASSERT_NEAR(emf(type, temperature(type, e)), e, 1e-9) << "type " << to_string(type) << " at " << e << " mV";
    }
  }
}

TEST(ThermocoupleRoundTrip, RangeEndsInvertToThemselves) {
  for (Type type : kAllTypes) {
    const TemperatureRange range = emf_to_temperature_range(type);
    EXPECT_NEAR(temperature(type, emf(type, range.low_c)), range.low_c, 1e-6) << to_string(type);
    EXPECT_NEAR(temperature(type, emf(type, range.high_c)), range.high_c, 1e-6) << to_string(type);
  }
}

TEST(ThermocoupleRanges, MatchNist) {
  const auto expect_range = [](TemperatureRange range, double low_c, double high_c, const std::string& what) {
    EXPECT_EQ(range.low_c, low_c) << what;
    EXPECT_EQ(range.high_c, high_c) << what;
  };
  expect_range(reference_function_range(Type::kB), 0.0, 1820.0, "B");
  expect_range(reference_function_range(Type::kE), -270.0, 1000.0, "E");
  expect_range(reference_function_range(Type::kJ), -210.0, 1200.0, "J");
  expect_range(reference_function_range(Type::kK), -270.0, 1372.0, "K");
  expect_range(reference_function_range(Type::kN), -270.0, 1300.0, "N");
  expect_range(reference_function_range(Type::kR), -50.0, 1768.1, "R");
  expect_range(reference_function_range(Type::kS), -50.0, 1768.1, "S");
  expect_range(reference_function_range(Type::kT), -270.0, 400.0, "T");
  expect_range(nist_inverse_range(Type::kK), -200.0, 1372.0, "K inverse");
  expect_range(emf_to_temperature_range(Type::kK), -270.0, 1372.0, "K served");
  expect_range(emf_to_temperature_range(Type::kB), 250.0, 1820.0, "B served");
}

// ------------------------------------------------------------- continuity

TEST(ThermocoupleContinuity, ReferenceFunctionsAreContinuousAtSubrangeBoundaries) {
  constexpr double kMicrovoltInMv = 1e-3;
  int boundaries = 0;
  for (Type type : kAllTypes) {
    const auto pieces = its90::coefficients(type).forward;
    for (std::size_t i = 1; i < pieces.size(); ++i) {
      const double boundary_c = pieces[i].low_c;
      const double below = emf(type, std::nextafter(boundary_c, -1e9));
      const double above = emf(type, std::nextafter(boundary_c, 1e9));
      EXPECT_NEAR(below, above, kMicrovoltInMv) << to_string(type) << " at " << boundary_c << " °C";
      ++boundaries;
    }
  }
  EXPECT_EQ(boundaries, 10);  // one per adjacent pair: two for R and S, one for the others
}

TEST(ThermocoupleContinuity, InverseIsContinuousWhereNistSubrangesMeet) {
  // The refined inverse must not jump where NIST's polynomials hand over
  // (K at 20.644 mV, R and S in their overlap around the gold point).
  for (Type type : kAllTypes) {
    for (const auto& piece : its90::coefficients(type).inverse) {
      const double e = piece.low_mv;
      if (!temperature_c_at(type, e).ok()) continue;
      const double below = temperature(type, std::nextafter(e, -1e9));
      const double above = temperature(type, std::nextafter(e, 1e9));
      EXPECT_NEAR(below, above, 1e-6) << to_string(type) << " at " << e << " mV";
    }
  }
}

// ------------------------------------------------ cold-junction compensation

TEST(ThermocoupleColdJunction, CompensationIsDoneInVoltage) {
  // A K thermocouple at 100 °C with its terminals at 25 °C produces
  // E(100) − E(25) = 4.096 − 1.000 = 3.096 mV (NIST type K table).
  const TemperatureResult from_table = compensated_temperature_c(Type::kK, 4.096 - 1.000, 25.0);
  ASSERT_TRUE(from_table.ok());
  EXPECT_NEAR(*from_table.temperature_c, 100.0, 2 * kTablePrecisionMv / seebeck_mv_per_c(Type::kK, 100.0));

  const double measured_mv = emf(Type::kK, 100.0) - emf(Type::kK, 25.0);
  EXPECT_NEAR(*compensated_temperature_c(Type::kK, measured_mv, 25.0).temperature_c, 100.0, 1e-6);
  // Adding the cold-junction temperature to the uncompensated reading is
  // what compensation must not do; it is wrong by more than 0.1 °C here.
  EXPECT_GT(std::abs(temperature(Type::kK, measured_mv) + 25.0 - 100.0), 0.1);
}

TEST(ThermocoupleColdJunction, RecoversHotJunctionForEveryTypeAndEitherSide) {
  for (Type type : kAllTypes) {
    const TemperatureRange range = emf_to_temperature_range(type);
    for (double cold_junction_c : {0.0, 21.5, 40.0}) {
      for (double hot_c : {range.low_c, 0.5 * (range.low_c + range.high_c), range.high_c - 1.0}) {
        const double measured_mv = emf(type, hot_c) - emf(type, cold_junction_c);
        const TemperatureResult result = compensated_temperature_c(type, measured_mv, cold_junction_c);
        ASSERT_TRUE(result.ok()) << to_string(type);
        EXPECT_NEAR(*result.temperature_c, hot_c, 1e-6) << to_string(type) << " cj " << cold_junction_c;
      }
    }
  }
}

TEST(ThermocoupleColdJunction, BadInputsGiveAStatusAndNoValue) {
  const auto expect_status = [](TemperatureResult result, SampleStatus status) {
    EXPECT_EQ(result.status, status);
    EXPECT_FALSE(result.temperature_c.has_value());
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  expect_status(compensated_temperature_c(Type::kK, nan, 25.0), SampleStatus::kInvalidValue);
  expect_status(compensated_temperature_c(Type::kK, 1.0, nan), SampleStatus::kInvalidValue);
  expect_status(compensated_temperature_c(Type::kK, 1.0, 2000.0), SampleStatus::kOutOfRange);
  expect_status(compensated_temperature_c(Type::kB, 5.0, -10.0), SampleStatus::kOutOfRange);
  // 54 mV on top of a 25 °C cold junction is beyond K's 1372 °C.
  expect_status(compensated_temperature_c(Type::kK, 54.0, 25.0), SampleStatus::kOutOfRange);
}

// ---------------------------------------------------------- status, parsing

TEST(ThermocoupleStatus, OutOfRangeAndNonFiniteInputsGiveNoValue) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (Type type : kAllTypes) {
    const TemperatureRange range = reference_function_range(type);
    for (double t : {std::nextafter(range.low_c, -1e9), std::nextafter(range.high_c, 1e9), -1000.0, 5000.0}) {
      const EmfResult result = emf_mv_at(type, t);
      EXPECT_EQ(result.status, SampleStatus::kOutOfRange) << to_string(type) << " " << t;
      EXPECT_FALSE(result.emf_mv.has_value());
    }
    for (double t : {nan, inf, -inf}) {
      const EmfResult result = emf_mv_at(type, t);
      EXPECT_EQ(result.status, SampleStatus::kInvalidValue) << to_string(type);
      EXPECT_FALSE(result.emf_mv.has_value());
    }
    const TemperatureRange served = emf_to_temperature_range(type);
    for (double e : {emf(type, served.low_c) - 1e-6, emf(type, served.high_c) + 1e-6, 100.0, -100.0}) {
      const TemperatureResult result = temperature_c_at(type, e);
      EXPECT_EQ(result.status, SampleStatus::kOutOfRange) << to_string(type) << " " << e << " mV";
      EXPECT_FALSE(result.temperature_c.has_value());
    }
    for (double e : {nan, inf, -inf}) {
      const TemperatureResult result = temperature_c_at(type, e);
      EXPECT_EQ(result.status, SampleStatus::kInvalidValue) << to_string(type);
      EXPECT_FALSE(result.temperature_c.has_value());
    }
  }
}

TEST(ThermocoupleStatus, TypeBIsNotInvertedWhereItsEmfIsAmbiguous) {
  // B's EMF dips below zero up to about 21 °C and is under 0.3 mV up to
  // 250 °C; a reading there cannot name one temperature.
  EXPECT_TRUE(emf_mv_at(Type::kB, 10.0).ok());
  EXPECT_LT(*emf_mv_at(Type::kB, 10.0).emf_mv, 0.0);
  EXPECT_EQ(temperature_c_at(Type::kB, 0.0).status, SampleStatus::kOutOfRange);
  EXPECT_EQ(temperature_c_at(Type::kB, 0.2).status, SampleStatus::kOutOfRange);
}

TEST(ThermocoupleTypeName, ParsesLetterNamesInEitherCase) {
  EXPECT_EQ(parse_thermocouple_type("K"), Type::kK);
  EXPECT_EQ(parse_thermocouple_type("k"), Type::kK);
  EXPECT_EQ(parse_thermocouple_type(" j "), Type::kJ);
  for (Type type : kAllTypes) EXPECT_EQ(parse_thermocouple_type(to_string(type)), type);
  for (const char* bad : {"", " ", "X", "C", "KK", "type K", "0"}) {
    EXPECT_FALSE(parse_thermocouple_type(bad).has_value()) << "'" << bad << "'";
  }
}

}  // namespace
}  // namespace bosfuse::acquisition
