#include "report/summary.h"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <sstream>

#include "fitting/uncertainty_digits.h"
#include "report/html.h"

namespace bosfuse::report {
namespace {

std::optional<double> finite(double v) { return std::isfinite(v) ? std::optional<double>(v) : std::nullopt; }

SummaryQuantity missing(std::string unit, std::string reason) {
  SummaryQuantity q;
  q.unit = std::move(unit);
  q.reason = std::move(reason);
  return q;
}

SummaryQuantity number(double value, std::string unit, std::string reason_if_not_finite) {
  if (!std::isfinite(value)) return missing(std::move(unit), std::move(reason_if_not_finite));
  SummaryQuantity q;
  q.value = value;
  q.unit = std::move(unit);
  return q;
}

SummaryQuantity from_estimate(const fitting::Estimate& e, std::string unit, const std::string& series) {
  SummaryQuantity q = number(e.value, std::move(unit), fmt::format("the fit of {} holds no finite value", series));
  if (!q.value) return q;
  q.fixed = e.fixed;
  if (e.fixed) return q;
  q.std_error = finite(e.std_error);
  q.low = finite(e.low);
  q.high = finite(e.high);
  return q;
}

bool fit_ok(const CurveSeries& s) { return s.fit && s.fit->ok(); }

std::string fit_failure(const CurveSeries& s) {
  if (!s.fit) return fmt::format("{} was not fitted", s.name);
  return fmt::format("the fit of {} failed ({}): {}", s.name, fitting::to_string(s.fit->summary.status),
                     s.fit->summary.message);
}

void set_fit_quantities(SeriesSummary& row, const CurveSeries& s) {
  if (!fit_ok(s)) {
    const std::string reason = fit_failure(s);
    for (auto* q : {&row.k, &row.tau, &row.t0, &row.ambient, &row.residual_rms}) *q = missing("", reason);
    row.k.unit = "1/s";
    row.tau.unit = "s";
    row.t0.unit = row.ambient.unit = row.residual_rms.unit = s.unit;
    return;
  }
  const auto& f = *s.fit;
  row.k = from_estimate(f.k_per_s, "1/s", s.name);
  row.tau = from_estimate(f.tau_s, "s", s.name);
  row.t0 = from_estimate(f.t0_c, s.unit, s.name);
  row.ambient = from_estimate(f.ambient_c, s.unit, s.name);
  row.residual_rms =
      number(f.summary.residual_rms_c, s.unit, fmt::format("the fit of {} holds no residual RMS", s.name));
}

std::vector<std::string> series_notes(const CurveSeries& s) {
  std::vector<std::string> notes;
  if (s.unit != "°C") {
    notes.push_back(
        fmt::format("in {} (shift magnitude, no calibration): T0, T_amb and the residual RMS are in {}, "
                    "not °C",
                    s.unit, s.unit));
  }
  if (fit_ok(s) && !s.fit->t0_at_origin()) {
    const auto& f = *s.fit;
    notes.push_back(
        fmt::format("T0 is at t = {} s, the series' first sample: the fit's origin (t = {} s) lies {} time "
                    "constants from the data, too far for T0 there",
                    display_number(f.origin_s + f.t0_reference_s, "{:.6g}"), display_number(f.origin_s, "{:.4g}"),
                    display_number(std::abs(f.t0_reference_s) / f.tau_s.value, "{:.3g}")));
  } else if (fit_ok(s) && s.fit->origin_s != 0.0) {
    notes.push_back(fmt::format("T0 is at t = {} s, the fit's origin", display_number(s.fit->origin_s, "{:.4g}")));
  }
  if (s.excluded_samples > 0) {
    notes.push_back(fmt::format("{} samples without a value (non-ok status) left out", s.excluded_samples));
  }
  if (fit_ok(s)) notes.insert(notes.end(), s.fit->summary.warnings.begin(), s.fit->summary.warnings.end());
  return notes;
}

SeriesSummary summarize_series(const CurveSeries& s) {
  SeriesSummary row;
  row.name = s.name;
  row.kind = s.kind;
  row.points = s.fit && s.fit->summary.points_used > 0 ? s.fit->summary.points_used : s.time_s.size();
  set_fit_quantities(row, s);
  row.notes = series_notes(s);
  return row;
}

const CurveSeries* find_series(const ReportInput& input, const std::string& name) {
  for (const auto& s : input.series) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

std::string no_k_reason(const AgreementEntry& e, const ReportInput& input) {
  for (const auto& name : {e.thermocouple, e.probe}) {
    const CurveSeries* s = find_series(input, name);
    if (!s) return fmt::format("no Δk: the report holds no series named {}", name);
    if (!fit_ok(*s)) return "no Δk: " + fit_failure(*s);
  }
  return "no Δk: a fit failed";
}

void set_k_quantities(PairSummary& p, const AgreementEntry& e, const ReportInput& input) {
  const auto& k = e.agreement.k;
  if (!k) {
    p.delta_k = missing("1/s", no_k_reason(e, input));
    p.z = missing("", p.delta_k.reason);
    return;
  }
  p.delta_k = number(k->difference_per_s, "1/s", "the stored agreement holds no finite Δk");
  if (p.delta_k.value) p.delta_k.std_error = finite(k->std_error_per_s);
  p.z = number(k->z, "", "no z: Δk has no finite, non-zero standard error");
  p.k_agree = k->agree;
}

const CurveSeries* non_celsius(const AgreementEntry& e, const ReportInput& input) {
  for (const auto& name : {e.thermocouple, e.probe}) {
    const CurveSeries* s = find_series(input, name);
    if (s && s->unit != "°C") return s;
  }
  return nullptr;
}

// Empty when the two can be compared as temperatures.
std::string no_difference_reason(const AgreementEntry& e, const ReportInput& input) {
  if (const CurveSeries* s = non_celsius(e, input)) {
    return fmt::format("Δk only: {} is in {}, not °C — no temperature difference", s->name, s->unit);
  }
  if (!e.agreement.series) return "no temperature difference: the two series share too few common times";
  return {};
}

const fitting::ParameterAgreement* k_test(const fitting::Agreement& a) {
  if (!a.curve) return nullptr;
  for (const auto& p : a.curve->parameters) {
    if (p.name == "k_per_s") return &p;
  }
  return nullptr;
}

// The stored verdict of a pair with a px series also judges T0 and T_amb
// and the temperature differences (°C against px, meaningless): it is
// replaced by the verdict on k alone and the reason. An agreement stored
// before the equivalence test has its k sentence first and the one on
// temperatures beginning with " On ".
std::string k_only_verdict(const fitting::Agreement& a, const std::string& name, const std::string& unit) {
  const std::string reason = fmt::format(" The temperatures are not compared: {} is in {}, not °C.", name, unit);
  if (const fitting::ParameterAgreement* k = k_test(a)) {
    const std::string word = fitting::to_string(k->verdict);
    return fmt::format("{}{} on k alone: k {} (Δ = {} ± {} 1/s, z = {}, margin ±{} 1/s).", char(std::toupper(word[0])),
                       word.substr(1), word, display_number(k->difference, "{:.3g}"),
                       display_number(k->std_error, "{:.2g}"), display_number(k->z, "{:.2f}"),
                       display_number(k->margin, "{:.2g}")) +
           reason;
  }
  const auto cut = a.verdict.find(" On ");
  return a.verdict.substr(0, cut == std::string::npos ? a.verdict.size() : cut + 1) + reason;
}

// The verdict word, what decided it and its z and margin; k's alone for a px probe.
void set_equivalence(PairSummary& p, const fitting::Agreement& a, bool k_only) {
  const fitting::ParameterAgreement* deciding = k_only ? k_test(a) : (a.curve ? a.curve->deciding() : nullptr);
  if (!deciding) {
    const std::string reason = a.curve ? "no parameter decided the verdict"
                               : a.k   ? "stored before the equivalence test: no verdict of agree, differ or "
                                         "inconclusive"
                                       : "no equivalence test: a fit failed";
    p.deciding_z = missing("", reason);
    p.margin = missing("", reason);
    return;
  }
  p.equivalence = fitting::to_string(k_only ? deciding->verdict : a.curve->verdict);
  const bool k = deciding->name == "k_per_s";
  p.deciding = k ? "k" : deciding->name == "T0_c" ? "T0" : "T_amb";
  p.deciding_z = number(deciding->z, "", "no z: the difference has no finite, non-zero standard error");
  p.margin = number(deciding->margin, k ? "1/s" : "°C", "no finite margin");
}

void set_difference_quantities(PairSummary& p, const AgreementEntry& e, const ReportInput& input) {
  if (const std::string reason = no_difference_reason(e, input); !reason.empty()) {
    p.rms_difference = missing("°C", reason);
    p.bias = missing("°C", reason);
    if (const CurveSeries* s = non_celsius(e, input)) p.verdict = k_only_verdict(e.agreement, s->name, s->unit);
    return;
  }
  const auto& d = *e.agreement.series;
  p.pairs = d.common_points;
  p.rms_difference = number(d.rms_difference_c, "°C", "the stored agreement holds no finite RMS difference");
  const bool limits = std::isfinite(d.limits_of_agreement_low_c) && std::isfinite(d.limits_of_agreement_high_c);
  p.bias = number(limits ? d.bias_c : NAN, "°C", "the stored agreement holds no finite bias and limits of agreement");
  if (!p.bias.value) return;
  p.bias.low = d.limits_of_agreement_low_c;
  p.bias.high = d.limits_of_agreement_high_c;
}

PairSummary summarize_pair(const AgreementEntry& e, const ReportInput& input) {
  PairSummary p;
  p.thermocouple = e.thermocouple;
  p.probe = e.probe;
  p.verdict = e.agreement.verdict;
  set_k_quantities(p, e, input);
  set_difference_quantities(p, e, input);
  set_equivalence(p, e.agreement, non_celsius(e, input) != nullptr);
  return p;
}

double fits_confidence(const ReportInput& input) {
  for (const auto& s : input.series) {
    if (fit_ok(s)) return s.fit->summary.confidence;
  }
  return 0.95;
}

// Reasons numbered in order of first use, each listed once under its table.
class Footnotes {
 public:
  std::string mark(const std::string& reason) {
    std::size_t i = 0;
    while (i < reasons_.size() && reasons_[i] != reason) ++i;
    if (i == reasons_.size()) reasons_.push_back(reason);
    return fmt::format("<sup>{}</sup>", i + 1);
  }
  std::string html() const {
    if (reasons_.empty()) return {};
    std::string h = "<ol class=\"footnotes\">";
    for (const auto& r : reasons_) h += "<li>" + html_escape(r) + "</li>";
    return h + "</ol>\n";
  }

 private:
  std::vector<std::string> reasons_;
};

// A value in a column whose header gives `column_unit`; another unit is
// written beside the value, so a px probe cannot pass for °C.
std::string cell(const SummaryQuantity& q, std::string_view format, const std::string& column_unit, Footnotes& notes,
                 bool with_interval = true) {
  if (!q.value) return "<td>—" + notes.mark(q.reason) + "</td>";
  const bool other_unit = q.unit != column_unit;
  if (other_unit) format = "{:.3g}";  // a px value has its own scale
  // A fitted value with its σ is written at the digits σ supports
  // (fitting/uncertainty_digits.h), its interval likewise; `format` serves
  // what has no σ.
  const bool at_sigma = !other_unit && !q.fixed && q.std_error && fitting::uncertainty_decimals(*q.std_error);
  const auto number = [&](double v) {
    return at_sigma && std::isfinite(v) ? fitting::format_at_uncertainty(v, *q.std_error) : display_number(v, format);
  };
  std::string text = number(*q.value);
  if (other_unit) text += " " + html_escape(q.unit);
  if (q.fixed) return "<td>" + text + " (fixed)</td>";
  if (with_interval && q.low && q.high) {
    text += fmt::format("<br><small>[{}, {}]</small>", number(*q.low), number(*q.high));
  }
  return "<td>" + text + "</td>";
}

std::string notes_cell(const std::vector<std::string>& notes) {
  std::string h = "<td class=\"text\">";
  for (std::size_t i = 0; i < notes.size(); ++i) h += (i ? "<br>" : "") + html_escape(notes[i]);
  return h + "</td>";
}

std::string series_row(const SeriesSummary& r, Footnotes& notes) {
  return "<tr><td class=\"text\">" + html_escape(r.name) + "</td><td class=\"text\">" + to_string(r.kind) +
         "</td><td>" + std::to_string(r.points) + "</td>" + cell(r.k, "{:.4g}", "1/s", notes) +
         cell(r.tau, "{:.4g}", "s", notes) + cell(r.t0, "{:.2f}", "°C", notes) +
         cell(r.ambient, "{:.2f}", "°C", notes) + cell(r.residual_rms, "{:.3g}", "°C", notes) + notes_cell(r.notes) +
         "</tr>\n";
}

std::string series_table(const ReportSummary& s) {
  if (s.series.empty()) return "<p class=\"note\">No temperature series to summarise.</p>\n";
  Footnotes notes;
  std::ostringstream h;
  h << "<table class=\"summary fits\"><caption>Newton fits T(t) = T_amb + (T0 − T_amb)·exp(−k·t), t in "
    << html_escape(s.time_basis) << fmt::format("; intervals at {:.0f}% from each fit's covariance", 100 * s.confidence)
    << " (scaled by the residual variance unless the measurement σ was given, docs/FITTING.md). "
       "“—”: not computed, for the reason in the footnote.</caption>\n"
       "<tr><th class=\"text\">series</th><th class=\"text\">kind</th><th>points</th><th>k (1/s)</th>"
       "<th>τ (s)</th><th>T0 (°C)</th><th>T_amb (°C)</th><th>residual RMS (°C)</th><th class=\"text\">notes</th>"
       "</tr>\n";
  for (const auto& r : s.series) h << series_row(r, notes);
  h << "</table>\n" << notes.html();
  return h.str();
}

std::string delta_k_cell(const SummaryQuantity& q, Footnotes& notes) {
  if (!q.value) return "<td>—" + notes.mark(q.reason) + "</td>";
  const std::string sigma = q.std_error ? " ± " + display_number(*q.std_error, "{:.2g}") : "";
  return "<td>" + display_number(*q.value, "{:.3g}") + sigma + "</td>";
}

std::string limits_cell(const SummaryQuantity& bias, Footnotes& notes) {
  if (!bias.value) return "<td>—" + notes.mark(bias.reason) + "</td>";
  return fmt::format("<td>[{}, {}]</td>", display_number(*bias.low, "{:.3g}"), display_number(*bias.high, "{:.3g}"));
}

// agree / differ / inconclusive, with what decided it, its z and margin.
std::string equivalence_cell(const PairSummary& p, Footnotes& notes) {
  if (p.equivalence.empty()) return "<td class=\"text\">—" + notes.mark(p.deciding_z.reason) + "</td>";
  std::string text = "<strong>" + html_escape(p.equivalence) + "</strong><br><small>by " + html_escape(p.deciding);
  if (p.deciding_z.value) text += ", z = " + display_number(*p.deciding_z.value, "{:.2f}");
  if (p.margin.value)
    text += ", margin ±" + display_number(*p.margin.value, "{:.2g}") + " " + html_escape(p.margin.unit);
  return "<td class=\"text\">" + text + "</small></td>";
}

// The verdict's sentences name every parameter's test: folded, so that a
// row stays a row and the figures below stay where a reader expects them.
std::string verdict_sentences_cell(const std::string& verdict) {
  return "<td class=\"text\"><details><summary>the test in words</summary>" + html_escape(verdict) + "</details></td>";
}

std::string pairs_count_cell(const PairSummary& p, Footnotes& notes) {
  if (!p.pairs) return "<td>—" + notes.mark(p.rms_difference.reason) + "</td>";
  return "<td>" + std::to_string(*p.pairs) + "</td>";
}

std::string pair_row(const PairSummary& p, Footnotes& notes) {
  return "<tr><td class=\"text\">" + html_escape(p.thermocouple) + "</td><td class=\"text\">" + html_escape(p.probe) +
         "</td>" + equivalence_cell(p, notes) + delta_k_cell(p.delta_k, notes) + cell(p.z, "{:.2f}", "", notes) +
         verdict_sentences_cell(p.verdict) + pairs_count_cell(p, notes) +
         cell(p.rms_difference, "{:.3g}", "°C", notes) + cell(p.bias, "{:.3g}", "°C", notes, false) +
         limits_cell(p.bias, notes) + "</tr>\n";
}

std::string pairs_table(const ReportSummary& s) {
  Footnotes notes;
  std::ostringstream h;
  h << "<table class=\"summary agreement\"><caption>Each thermocouple against the BOS probe at its position. "
       "Verdict: each of k, T0 and T_amb agrees when the 90% interval of its difference (two one-sided tests at "
       "α = 0.05) lies inside ±margin, "
       "differs when it lies wholly outside, and is inconclusive otherwise; the curve takes the worst of them "
       "(by: the parameter that decided it, its z = difference/σ and margin). The thermocouple's response lag "
       "is removed first (docs/FITTING.md). Δk = k_thermocouple − k_probe ± its combined standard error σ, "
       "z = Δk/σ; the temperature differences thermocouple − probe at the BOS frame times within their overlap "
       "(thermocouple interpolated; n pairs), t in "
    << html_escape(s.time_basis)
    << ": RMS, Bland–Altman bias and 95% limits of agreement. “—”: not computed, for the reason in the "
       "footnote.</caption>\n"
       "<tr><th class=\"text\">thermocouple</th><th class=\"text\">BOS probe</th><th class=\"text\">verdict</th>"
       "<th>Δk ± σ (1/s)</th><th>z</th><th class=\"text\">in words</th><th>n</th><th>RMS difference (°C)</th>"
       "<th>bias (°C)</th><th>95% limits of agreement (°C)</th></tr>\n";
  for (const auto& p : s.pairs) h << pair_row(p, notes);
  h << "</table>\n" << notes.html();
  return h.str();
}

}  // namespace

ReportSummary summarize(const ReportInput& input) {
  ReportSummary summary;
  summary.time_basis = input.time_basis;
  summary.confidence = fits_confidence(input);
  for (const auto& s : input.series) summary.series.push_back(summarize_series(s));
  for (const auto& e : input.agreements) summary.pairs.push_back(summarize_pair(e, input));
  return summary;
}

std::string summary_html(const ReportSummary& summary) {
  return series_table(summary) + (summary.pairs.empty() ? std::string() : pairs_table(summary));
}

}  // namespace bosfuse::report
