// Critical values against printed tables (e.g. NIST/SEMATECH e-Handbook,
// table 1.3.6.7.2), to the 4–6 digits the tables give.

#include "fitting/student_t.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace bosfuse::fitting {
namespace {

TEST(StudentT, CriticalValuesMatchTables) {
  EXPECT_NEAR(student_t_critical(1, 0.95), 12.706, 1e-3);
  EXPECT_NEAR(student_t_critical(2, 0.95), 4.303, 1e-3);
  EXPECT_NEAR(student_t_critical(10, 0.95), 2.228, 1e-3);
  EXPECT_NEAR(student_t_critical(30, 0.99), 2.750, 1e-3);
  EXPECT_NEAR(student_t_critical(100, 0.90), 1.660, 1e-3);
  EXPECT_NEAR(student_t_critical(1e6, 0.95), 1.959966, 1e-5) << "tends to the normal value";
}

TEST(StudentT, NormalCriticalValues) {
  EXPECT_NEAR(normal_critical(0.95), 1.959964, 1e-6);
  EXPECT_NEAR(normal_critical(0.99), 2.575829, 1e-6);
  EXPECT_NEAR(normal_critical(0.6826895), 1.0, 1e-6);
}

TEST(StudentT, CdfIsSymmetricAndMonotonic) {
  EXPECT_DOUBLE_EQ(student_t_cdf(0.0, 5), 0.5);
  EXPECT_NEAR(student_t_cdf(2.015, 5), 0.95, 1e-4);
  EXPECT_NEAR(student_t_cdf(-2.015, 5) + student_t_cdf(2.015, 5), 1.0, 1e-12);
  double previous = 0.0;
  for (int i = -50; i <= 50; ++i) {
    const double p = student_t_cdf(0.2 * i, 3);
    EXPECT_GE(p, previous);
    previous = p;
  }
}

TEST(StudentT, RefusesMeaninglessArguments) {
  EXPECT_THROW(student_t_critical(0, 0.95), std::invalid_argument);
  EXPECT_THROW(student_t_critical(5, 1.0), std::invalid_argument);
  EXPECT_THROW(normal_critical(0.0), std::invalid_argument);
}

}  // namespace
}  // namespace bosfuse::fitting
