#pragma once
// Student's t distribution: the two-sided critical value that turns a
// standard error into a confidence interval when the noise level was itself
// estimated from n − p residuals. Use student_t_critical(dof, 0.95) for a
// 95% interval; for large dof it tends to the normal 1.96. Self-contained
// (regularised incomplete beta by continued fraction) so fitting/ needs no
// statistics library.

namespace bosfuse::fitting {

// P(T <= t) for T ~ Student t with `dof` > 0 degrees of freedom.
double student_t_cdf(double t, double dof);

// The value c with P(|T| <= c) = confidence, for 0 < confidence < 1.
double student_t_critical(double dof, double confidence);

// The same for the standard normal distribution (infinite dof).
double normal_critical(double confidence);

}  // namespace bosfuse::fitting
