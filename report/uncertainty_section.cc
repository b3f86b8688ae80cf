#include "report/uncertainty_section.h"

#include <fmt/format.h>

#include "report/html.h"

namespace bosfuse::report {
namespace {

std::string esc(const std::string& text) { return html_escape(text); }

std::string g3(double v) { return display_number(v, "{:.3g}"); }

std::string budget_table(const fusion::TemperatureBudget& b, const std::string& basis) {
  std::string h = "<h3>Type-B budget of a BOS temperature</h3>\n<p>" + esc(basis) +
                  ". Each input's standard uncertainty times the sensitivity of the temperature to it, combined as "
                  "the root sum of squares (GUM, JCGM 100:2008 §5.1, the inputs uncorrelated). No number of frames "
                  "averages these away.</p>\n";
  h += fmt::format(
      "<table class=\"budget\"><tr><th class=\"text\">input</th><th>standard uncertainty</th><th>sensitivity</th>"
      "<th>contribution at {} °C</th></tr>\n",
      display_number(b.temperature_c, "{:.2f}"));
  for (const auto& c : b.components) {
    h += fmt::format("<tr><td class=\"text\">{}</td><td>{} {}</td><td>{} °C per {}</td><td>{} °C</td></tr>\n",
                     esc(c.quantity), g3(c.standard_uncertainty), esc(c.unit), g3(c.sensitivity),
                     esc(c.unit == "relative" ? "unit" : c.unit), display_number(c.contribution_c, "{:.3f}"));
  }
  h += fmt::format(
      "<tr><td class=\"text\"><b>combined (root sum of squares)</b></td><td></td><td></td><td><b>{} °C</b></td>"
      "</tr></table>\n",
      display_number(b.combined_c, "{:.3f}"));
  return h;
}

std::string probes_table(const std::vector<ProbeUncertainty>& probes) {
  std::string h =
      "<h3>Random uncertainty of each probe</h3>\n<p>The random standard uncertainty of each sample's temperature: "
      "the vectors' σ propagated exactly through the temperature solve to the probe's interpolated value (or "
      "through the calibration's slope). It weights the probe's fit.</p>\n"
      "<table class=\"probe-sigma\"><tr><th class=\"text\">probe</th><th>samples with σ</th><th>median σ random</th>"
      "<th>largest σ random</th><th>median σ systematic</th></tr>\n";
  for (const auto& p : probes) {
    const bool any = p.samples_with_sigma > 0;
    h += fmt::format("<tr><td class=\"text\">{}</td><td>{} of {}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
                     esc(p.probe), p.samples_with_sigma, p.samples, any ? g3(p.median_random_c) + " °C" : "—",
                     any ? g3(p.max_random_c) + " °C" : "—",
                     p.median_systematic_c ? g3(*p.median_systematic_c) + " °C" : "—");
  }
  return h + "</table>\n";
}

std::string fits_table(const std::vector<FitInterval>& fits) {
  std::string h =
      "<h3>Fits: random, systematic and combined</h3>\n<p>Each BOS probe's fitted parameters with the fit's "
      "standard error (random), the systematic part (the budget propagated through the fit: each input shifts the "
      "series and the fit is repeated) and the combined interval, value ± the fit's critical value × "
      "√(random² + systematic²).</p>\n"
      "<table class=\"fit-sigma\"><tr><th class=\"text\">series</th><th class=\"text\">parameter</th><th>value</th>"
      "<th>σ random</th><th>σ systematic</th><th>combined interval</th></tr>\n";
  for (const auto& f : fits) {
    h += fmt::format(
        "<tr><td class=\"text\">{}</td><td class=\"text\">{}</td><td>{} {}</td><td>{}</td><td>{}</td>"
        "<td>[{}, {}] {} ({:.0f} %)</td></tr>\n",
        esc(f.series), esc(f.parameter), g3(f.value), esc(f.unit), g3(f.std_error),
        f.systematic ? g3(*f.systematic) : "—", g3(f.low), g3(f.high), esc(f.unit), 100 * f.confidence);
  }
  return h + "</table>\n";
}

}  // namespace

std::string uncertainty_html(const UncertaintySummary& u) {
  std::string h = "<h2 id=\"uncertainty\">Uncertainty of the BOS temperatures</h2>\n";
  for (const auto& note : u.notes) h += "<p class=\"note\">" + esc(note) + "</p>\n";
  if (u.budget) h += budget_table(*u.budget, u.budget_basis);
  if (!u.probes.empty()) h += probes_table(u.probes);
  if (!u.fits.empty()) h += fits_table(u.fits);
  return h;
}

}  // namespace bosfuse::report
