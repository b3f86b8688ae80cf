// The report's uncertainty section, checked by its text: the budget table
// row by row with its combined value, the probes' σ, the fits' intervals.

#include "report/uncertainty_section.h"

#include <gtest/gtest.h>

#include <fmt/format.h>

namespace bosfuse::report {
namespace {

TEST(UncertaintySection, TheBudgetTableHasEveryInputItsContributionAndTheCombined) {
  fusion::BosGeometryOptions setup;
  setup.ambient_temperature_c = 21.0;
  const fusion::BosGeometry geometry(setup);
  UncertaintySummary u;
  u.budget = fusion::temperature_budget(geometry, {}, 61.0);
  u.budget_basis = "At 61.00 °C, the hottest BOS probe sample";
  u.probes.push_back({"tc0 (BOS)", 40, 38, 0.021, 0.05, 2.6});
  u.fits.push_back({"tc0 (BOS)", "T0", "°C", 80.1, 0.12, 2.5, 75.2, 85.0, 0.95});
  const std::string html = uncertainty_html(u);
  EXPECT_NE(html.find("<h3>Type-B budget of a BOS temperature</h3>"), std::string::npos);
  EXPECT_NE(html.find("<th>contribution at 61.00 °C</th>"), std::string::npos) << html;
  for (const auto& c : u.budget->components) {
    EXPECT_NE(html.find(fmt::format("<td class=\"text\">{}</td>", c.quantity)), std::string::npos) << c.quantity;
    EXPECT_NE(html.find(fmt::format("<td>{:.3f} °C</td>", c.contribution_c)), std::string::npos) << c.quantity;
  }
  EXPECT_NE(html.find(fmt::format("<b>{:.3f} °C</b>", u.budget->combined_c)), std::string::npos) << html;
  EXPECT_NEAR(u.budget->combined_c, 2.6, 0.1) << "docs/UNCERTAINTY.md's worked figure at 61 °C in a 21 °C room";
  EXPECT_NE(html.find("<td class=\"text\">tc0 (BOS)</td><td>38 of 40</td><td>0.021 °C</td><td>0.05 °C</td>"
                      "<td>2.6 °C</td>"),
            std::string::npos)
      << html;
  EXPECT_NE(html.find("<td>80.1 °C</td><td>0.12</td><td>2.5</td><td>[75.2, 85] °C (95 %)</td>"), std::string::npos)
      << html;
}

TEST(UncertaintySection, WithoutNumbersOnlyTheNotesShow) {
  UncertaintySummary u;
  u.notes.push_back("The stored BOS samples carry no uncertainty");
  const std::string html = uncertainty_html(u);
  EXPECT_NE(html.find("The stored BOS samples carry no uncertainty"), std::string::npos);
  EXPECT_EQ(html.find("<table"), std::string::npos) << "no table of numbers that do not exist";
}

}  // namespace
}  // namespace bosfuse::report
