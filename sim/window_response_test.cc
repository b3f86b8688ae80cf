#include "sim/window_response.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "fusion/temperature_budget.h"

namespace bosfuse::sim {
namespace {

CurvatureFit print(const char* label, const std::vector<WindowResponse>& rs) {
  for (const auto& r : rs) {
    fmt::print("{}: lambda {:.0f} px gain {:.4f} +- {:.4f} w_eff {:.2f} +- {:.2f} px ({} vectors)\n", label,
               r.wavelength_px, r.gain, r.gain_std_error, r.effective_window_px, r.effective_window_std_error_px,
               r.vectors);
  }
  const CurvatureFit fit = fit_curvature(rs);
  fmt::print("{}: kappa {:.2f} +- {:.2f} px2, w_eff {:.2f} px, gain without curvature {:.4f}\n", label, fit.kappa_px2,
             fit.kappa_std_error_px2, fit.effective_window_px(), fit.flat_gain);
  return fit;
}

// Without deformation the window is a box: its width is measured back
// (within 20 %), which checks the measurement itself.
TEST(WindowResponse, AWindowWithoutDeformationIsItsBox) {
  for (const int window : {16, 32}) {
    WindowResponseCase c;
    c.evaluator.xcorr.deform = false;
    c.evaluator.set_grid(window, window / 2);
    c.size_px = 16 * window;
    c.wavelengths_px = {6.0 * window, 8.0 * window, 12.0 * window};
    const auto fit = print(window == 16 ? "16 px, no deformation" : "32 px, no deformation",
                           measure_window_response(c));
    EXPECT_NEAR(fit.effective_window_px(), window, 0.2 * window);
  }
}

// The default chain's deformed windows barely average: the measured
// κ = w_eff²/24 lies within 2 σ of what fusion/temperature_budget.h states
// for them (the grid step 0: the evaluator's part alone).
TEST(WindowResponse, TheDefaultDeformedWindowBarelyAverages) {
  for (const int window : {16, 32}) {
    WindowResponseCase c;
    c.evaluator.set_grid(window, window / 2);
    c.size_px = 16 * window;
    c.wavelengths_px = {6.0 * window, 8.0 * window, 12.0 * window};
    const auto fit = print(window == 16 ? "16 px, 3 deformed passes" : "32 px, 3 deformed passes",
                           measure_window_response(c));
    const auto stated = fusion::chain_curvature_coefficient(c.evaluator, 0);
    EXPECT_LT(std::abs(fit.kappa_px2 - stated.kappa_px2), 2 * stated.sigma_px2);
  }
}

}  // namespace
}  // namespace bosfuse::sim
