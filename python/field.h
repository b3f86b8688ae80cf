#pragma once
// Field: a displacement field as NumPy arrays, each shaped (ny, nx) in the
// row order of `bosfuse evaluate`'s CSV (pipeline/field_csv.h): x, y, u, v,
// valid, flag, peak_ratio, sigma_u, sigma_v. A probe-mode field is one row
// of the probes in their order. `flag` holds the codes of
// fusion::VectorFlag (bosfuse.FLAG_NAMES gives their names).

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>

#include "fusion/displacement_field.h"

namespace bosfuse::python {

struct Field {
  pybind11::array_t<double> x, y, u, v, peak_ratio, sigma_u, sigma_v;
  pybind11::array_t<bool> valid;
  pybind11::array_t<std::uint8_t> flag;
  std::string summary;  // the evaluation's one-line report, empty for a stored field
  double seconds = 0;   // the library's own time for the evaluation (0 for a stored field)

  static Field from(const fusion::DisplacementField& field, std::string summary = {}, double seconds = 0);
  // Back to the library's form (a temperature solve of it); ValueError when
  // the arrays' shapes differ or a flag code is none of VectorFlag's.
  fusion::DisplacementField to_displacement() const;
};

}  // namespace bosfuse::python
