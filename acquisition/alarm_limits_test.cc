#include "acquisition/alarm_limits.h"

#include <gtest/gtest.h>

#include <cmath>

namespace bosfuse::acquisition {
namespace {

TEST(AlarmLimits, ValidateNamesTheKey) {
  EXPECT_EQ(AlarmLimits{}.Validate(), "");
  EXPECT_FALSE(AlarmLimits{}.any());
  EXPECT_EQ((AlarmLimits{1.0, 2.0, 3.0, 4.0}.Validate()), "");
  EXPECT_EQ((AlarmLimits{2.0, 1.0, {}, {}}.Validate()), "alarm_high: must be above alarm_low (2)");
  EXPECT_EQ((AlarmLimits{{}, std::nan(""), {}, {}}.Validate()), "alarm_high: expected a finite number");
  EXPECT_EQ((AlarmLimits{{}, {}, {}, 0.0}.Validate()).substr(0, 14), "alarm_stale_s:");
}

}  // namespace
}  // namespace bosfuse::acquisition
