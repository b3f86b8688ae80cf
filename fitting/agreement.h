#pragma once
// How well two measurements of one cooling process agree, typically a
// thermocouple and the BOS probe at its image position. Use compare_fits()
// once both series have been fitted with fit_newton(): it compares the two
// fitted k with their combined uncertainty (difference, z-score), and the
// two temperature series directly on common times (the second series is
// interpolated linearly onto the first one's times where they overlap):
// RMS difference, Bland–Altman bias and 95% limits of agreement. The verdict
// says in one sentence whether k agrees within uncertainty and, if not, by
// how much it differs.
//
// The two fits' uncertainties are taken as independent (different sensors,
// different noise). Times of both series are in one time base (e.g. seconds
// since the run's origin, or epoch seconds); each series keeps its own
// origin, which compare_fits() accounts for.

#include <cstddef>
#include <optional>
#include <string>

#include "fitting/newton_fit.h"
#include "fitting/series.h"

namespace bosfuse::fitting {

struct AgreementOptions {
  double confidence = 0.95;           // of the k test and the limits of agreement
  std::size_t min_common_points = 3;  // fewer common times: no series statistics
  std::string label_a = "thermocouple";
  std::string label_b = "BOS probe";

  // Empty when usable, else the reason.
  std::string invalid_reason() const;
};

// Statistics of the paired differences a − b on a's times within the overlap.
struct SeriesAgreement {
  std::size_t common_points = 0;
  double overlap_start_s = 0.0;  // in a's time base (relative to a's origin)
  double overlap_end_s = 0.0;
  double rms_difference_c = 0.0;
  double bias_c = 0.0;                      // mean of a − b
  double difference_std_c = 0.0;            // sample standard deviation of a − b
  double limits_of_agreement_low_c = 0.0;   // bias − z·sd (Bland–Altman)
  double limits_of_agreement_high_c = 0.0;  // bias + z·sd
};

struct KAgreement {
  double difference_per_s = 0.0;     // k_a − k_b
  double std_error_per_s = 0.0;      // sqrt(se_a² + se_b²)
  double z = 0.0;                    // difference / std_error
  double relative_difference = 0.0;  // difference / mean of the two k
  bool agree = false;                // |z| within the two-sided critical value
};

struct Agreement {
  std::optional<KAgreement> k;            // nullopt when a fit failed
  std::optional<SeriesAgreement> series;  // nullopt when the series share too few times
  std::string verdict;                    // one or two plain sentences

  std::string brief_report() const;
};

Agreement compare_fits(const NewtonFit& a, const NewtonFit& b, const CleanSeries& a_series, const CleanSeries& b_series,
                       const AgreementOptions& options = {});

// Paired-difference statistics only (no fits needed).
std::optional<SeriesAgreement> compare_series(const CleanSeries& a, const CleanSeries& b, double confidence = 0.95,
                                              std::size_t min_common_points = 3);

}  // namespace bosfuse::fitting
