#pragma once
// A measured value written at the digits its uncertainty supports: the
// standard uncertainty to two significant digits and the value (and its
// interval's ends) rounded to the same decimal place, as the GUM (JCGM
// 100:2008, 7.2.6) advises, so `k = 0.012293 ± 0.000035 1/s` rather than
// `0.0122926 ± 3.5e-05`. Used where a person reads a fit (`bosfuse fit`,
// `process`); the JSON keeps every bit.

#include <optional>
#include <string>

namespace bosfuse::fitting {

// The decimals that keep two significant digits of `std_error` (0.000035:
// 6; 0.23: 2; 3.5: 1; 35 and coarser: 0); none for a σ that is not a finite
// positive number, or one so small that fixed notation would be unreadable.
std::optional<int> uncertainty_decimals(double std_error);

// `value` at those decimals; at 6 significant digits when there are none.
std::string format_at_uncertainty(double value, double std_error);

}  // namespace bosfuse::fitting
