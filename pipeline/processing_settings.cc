#include "pipeline/processing_settings.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "acquisition/clock.h"
#include "acquisition/config/toml_reader.h"
#include "storage/processing_store.h"
#include "storage/run_paths.h"
#include "storage/run_store.h"

namespace bosfuse::pipeline {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

ProcessingSettings defaults() {
  ProcessingSettings s;
  s.evaluator.set_grid(16, 8);
  return s;
}

json uncertainty_json(const fusion::TypeBUncertainties& u) {
  return {{"gladstone_dale_relative", u.gladstone_dale_relative},
          {"ambient_pressure_pa", u.ambient_pressure_pa},
          {"ambient_temperature_c", u.ambient_temperature_c},
          {"z_d_relative", u.z_d_relative},
          {"magnification_relative", u.magnification_relative},
          {"depth_relative", u.depth_relative}};
}

// Settings stored before the budget existed have none: the defaults.
fusion::TypeBUncertainties uncertainty_from_json(const nlohmann::json& geometry) {
  fusion::TypeBUncertainties u;
  if (!geometry.contains("uncertainty")) return u;
  const nlohmann::json& j = geometry.at("uncertainty");
  u.gladstone_dale_relative = j.at("gladstone_dale_relative").get<double>();
  u.ambient_pressure_pa = j.at("ambient_pressure_pa").get<double>();
  u.ambient_temperature_c = j.at("ambient_temperature_c").get<double>();
  u.z_d_relative = j.at("z_d_relative").get<double>();
  u.magnification_relative = j.at("magnification_relative").get<double>();
  u.depth_relative = j.at("depth_relative").get<double>();
  return u;
}

json geometry_json(const GeometryConfig& g) {
  const auto& o = g.geometry;
  json edges = json::array();
  const auto& f = g.temperature_field;
  for (const auto& [open, name] :
       {std::pair{f.open_top, "top"}, {f.open_bottom, "bottom"}, {f.open_left, "left"}, {f.open_right, "right"}}) {
    if (open) edges.push_back(name);
  }
  return {{"wavelength_nm", o.wavelength_nm},
          {"ambient_pressure_pa", o.ambient_pressure_pa},
          {"ambient_temperature_c", o.ambient_temperature_c},
          {"ambient_given", g.ambient_given},
          {"z_d_m", o.z_d_m},
          {"depth_m", o.depth_m},
          {"magnification", o.magnification},
          {"pixel_pitch_um", o.pixel_pitch_um},
          {"px_per_mm_flow", o.px_per_mm_flow},
          {"open_edges", edges},
          {"camera_offset_s", g.camera_offset_s},
          {"source", g.source},
          {"uncertainty", uncertainty_json(g.uncertainty)}};
}

GeometryConfig geometry_from_json(const nlohmann::json& j) {
  GeometryConfig g;
  auto& o = g.geometry;
  o.wavelength_nm = j.at("wavelength_nm").get<double>();
  o.ambient_pressure_pa = j.at("ambient_pressure_pa").get<double>();
  o.ambient_temperature_c = j.at("ambient_temperature_c").get<double>();
  g.ambient_given = j.at("ambient_given").get<bool>();
  o.z_d_m = j.at("z_d_m").get<double>();
  o.depth_m = j.at("depth_m").get<double>();
  o.magnification = j.at("magnification").get<double>();
  o.pixel_pitch_um = j.at("pixel_pitch_um").get<double>();
  o.px_per_mm_flow = j.at("px_per_mm_flow").get<double>();
  for (const auto& edge : j.at("open_edges")) {
    const auto name = edge.get<std::string>();
    auto& f = g.temperature_field;
    (name == "top" ? f.open_top : name == "bottom" ? f.open_bottom : name == "left" ? f.open_left : f.open_right) =
        true;
  }
  g.camera_offset_s = j.at("camera_offset_s").get<double>();
  g.source = j.at("source").get<std::string>();
  g.uncertainty = uncertainty_from_json(j);
  return g;
}

// The mask as the run will store it: a path relative to the run folder.
std::string mask_in_run(const fs::path& run_dir, const std::string& given) {
  const fs::path path(given);
  if (!path.is_absolute()) {
    storage::resolve_in_run(run_dir, given);  // throws for a path that leads outside the run
    if (!fs::is_regular_file(run_dir / path)) {
      throw std::runtime_error("mask '" + given + "': no such file in the run folder " + run_dir.string() +
                               " (a relative mask path is relative to the run folder)");
    }
    return given;
  }
  if (!fs::is_regular_file(path)) throw std::runtime_error("mask '" + given + "': no such file");
  const fs::path relative = fs::weakly_canonical(path).lexically_relative(fs::weakly_canonical(run_dir));
  if (!relative.empty() && *relative.begin() != "..") return relative.string();
  // A file outside the run: the run keeps its own copy, so it stays self-describing.
  const fs::path copy = fs::path("masks") / path.filename();
  fs::create_directories(run_dir / "masks");
  fs::copy_file(path, run_dir / copy, fs::copy_options::overwrite_existing);
  return copy.string();
}

fusion::Preprocessing preprocessing_named(const std::string& name) {
  const auto method = fusion::parse_preprocessing(name);
  if (!method) {
    throw std::runtime_error("preprocess must be one of " + fusion::preprocessing_names() + ", not \"" + name + "\"");
  }
  return *method;
}

// The first pass's search a processing found from the scene (search_range.h),
// stored with its settings so that later frames, a resume and the next
// processing reuse it instead of sampling the scene again.
nlohmann::ordered_json search_json(const fusion::SearchRange& r) {
  return {{"given_max_shift_px", r.given_max_shift_px}, {"max_shift_px", r.max_shift_px},
          {"first_window_px", r.first_window_px},       {"widened", r.widened},
          {"beyond_reach", r.beyond_reach},             {"sampled", r.sampled},
          {"on_bound", r.on_bound},                     {"largest_px", r.largest_px}};
}

fusion::SearchRange search_from_json(const nlohmann::json& j) {
  fusion::SearchRange r;
  r.given_max_shift_px = j.at("given_max_shift_px").get<double>();
  r.max_shift_px = j.at("max_shift_px").get<double>();
  r.first_window_px = j.at("first_window_px").get<int>();
  r.widened = j.at("widened").get<bool>();
  r.beyond_reach = j.at("beyond_reach").get<bool>();
  r.sampled = j.at("sampled").get<int>();
  r.on_bound = j.at("on_bound").get<int>();
  r.largest_px = j.at("largest_px").get<double>();
  return r;
}

// Whether an override changes what the scene's search sees or starts from:
// then a stored search no longer holds and the next frame samples again.
bool changes_search(const SettingsOverrides& o) {
  return o.method || o.window_px || o.step_px || o.roi_px || o.max_shift_px || o.preprocess || o.mask;
}

// Everything but the files (mask, geometry), whose places differ with and without a run.
void apply_evaluator(const SettingsOverrides& o, ProcessingSettings& s) {
  if (o.probes_only) s.probes_only = *o.probes_only;
  if (changes_search(o)) s.evaluator.xcorr.known_search.reset();
  if (o.method) {
    if (*o.method != "xcorr" && *o.method != "flow") throw std::runtime_error("method must be xcorr or flow");
    s.evaluator.method = *o.method == "flow" ? fusion::Method::kOpticalFlow : fusion::Method::kCrossCorrelation;
  }
  if (o.flow_algorithm) {
    const auto algorithm = fusion::parse_flow_algorithm(*o.flow_algorithm);
    if (!algorithm) throw std::runtime_error("flow algorithm must be dis, farneback or tvl1");
    s.evaluator.flow.algorithm = *algorithm;
  }
  if (o.window_px || o.step_px || o.roi_px) {
    s.evaluator.set_grid(o.window_px.value_or(s.evaluator.xcorr.window_px),
                         o.step_px.value_or(s.evaluator.xcorr.step_px), o.roi_px.value_or(s.evaluator.xcorr.roi));
  }
  if (o.passes) s.evaluator.xcorr.passes = *o.passes;
  if (o.probe_context_nodes) s.evaluator.xcorr.probe_context_nodes = *o.probe_context_nodes;
  if (o.max_shift_px) {
    // A bound the user gives is explicit: the scene does not widen it.
    s.evaluator.xcorr.max_shift_px = *o.max_shift_px;
    s.evaluator.xcorr.find_search_range = false;
  }
  if (o.adaptive_refinement) s.evaluator.xcorr.adaptive_refinement = *o.adaptive_refinement;
  if (o.adaptive_threshold) s.evaluator.xcorr.adaptive_threshold = *o.adaptive_threshold;
  if (o.preprocess) s.evaluator.preprocess.method = preprocessing_named(*o.preprocess);
}

void apply(const SettingsOverrides& o, const fs::path& run_dir, const std::string& run_config, ProcessingSettings& s) {
  apply_evaluator(o, s);
  if (o.mask) s.mask = o.mask->empty() ? std::string() : mask_in_run(run_dir, *o.mask);
  if (o.geometry_file) s.geometry = resolve_geometry_config(*o.geometry_file, run_config);
}

}  // namespace

bool SettingsOverrides::empty() const {
  return !probes_only && !method && !flow_algorithm && !window_px && !step_px && !passes && !probe_context_nodes &&
         !max_shift_px && !adaptive_refinement && !adaptive_threshold && !preprocess && !roi_px && !mask &&
         !geometry_file;
}

std::string ProcessingSettings::Validate() const {
  if (auto problem = evaluator.Validate(); !problem.empty()) return problem;
  return geometry.geometry.Validate();
}

json to_json(const ProcessingSettings& s) {
  const auto& x = s.evaluator.xcorr;
  json j = {{"mode", s.probes_only ? "probes" : "full"},
            {"method", s.evaluator.method == fusion::Method::kOpticalFlow ? "flow" : "xcorr"},
            {"flow_algorithm", fusion::to_string(s.evaluator.flow.algorithm)},
            {"window_px", x.window_px},
            {"step_px", x.step_px},
            {"passes", x.passes},
            {"max_shift_px", x.max_shift_px},
            {"find_search_range", x.find_search_range},
            {"probe_context_nodes", x.probe_context_nodes},
            {"adaptive_refinement", x.adaptive_refinement},
            {"adaptive_threshold", x.adaptive_threshold},
            {"preprocess", std::string(fusion::to_string(s.evaluator.preprocess.method))}};
  if (x.find_search_range && x.known_search) j["found_search"] = search_json(*x.known_search);
  if (!x.roi.empty()) j["roi_px"] = {x.roi.x, x.roi.y, x.roi.width, x.roi.height};
  if (!s.mask.empty()) j["mask"] = s.mask;
  j["geometry"] = geometry_json(s.geometry);
  return j;
}

ProcessingSettings settings_from_json(const nlohmann::json& j) {
  try {
    ProcessingSettings s = defaults();
    s.probes_only = j.at("mode").get<std::string>() == "probes";
    s.evaluator.method =
        j.at("method").get<std::string>() == "flow" ? fusion::Method::kOpticalFlow : fusion::Method::kCrossCorrelation;
    s.evaluator.flow.algorithm = fusion::parse_flow_algorithm(j.at("flow_algorithm").get<std::string>()).value();
    cv::Rect roi;
    if (j.contains("roi_px")) {
      const auto& r = j.at("roi_px");
      roi = cv::Rect(r.at(0).get<int>(), r.at(1).get<int>(), r.at(2).get<int>(), r.at(3).get<int>());
    }
    s.evaluator.set_grid(j.at("window_px").get<int>(), j.at("step_px").get<int>(), roi);
    s.evaluator.xcorr.passes = j.at("passes").get<int>();
    s.evaluator.xcorr.max_shift_px = j.at("max_shift_px").get<double>();
    // Settings stored before the scene set the search: their bound was explicit.
    s.evaluator.xcorr.find_search_range = j.value("find_search_range", false);
    if (j.contains("found_search")) s.evaluator.xcorr.known_search = search_from_json(j.at("found_search"));
    s.evaluator.xcorr.probe_context_nodes = j.at("probe_context_nodes").get<int>();
    // Settings stored before adaptive refinement existed: it was off.
    s.evaluator.xcorr.adaptive_refinement = j.value("adaptive_refinement", false);
    s.evaluator.xcorr.adaptive_threshold = j.value("adaptive_threshold", s.evaluator.xcorr.adaptive_threshold);
    // Settings stored before preprocessing existed: there was none.
    s.evaluator.preprocess.method = preprocessing_named(j.value("preprocess", std::string("none")));
    s.mask = j.value("mask", std::string());
    s.geometry = geometry_from_json(j.at("geometry"));
    return s;
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string("stored processing settings are not of this bosfuse's layout: ") + e.what());
  }
}

ProcessingSettings resolve_settings(const fs::path& run_dir, const SettingsOverrides& overrides) {
  const storage::ProcessingStore results(run_dir);
  const auto store = storage::RunStore::open(run_dir);
  const std::string run_config = store.run().config_toml;
  ProcessingSettings s;
  if (const auto stored = results.latest_settings()) {
    s = settings_from_json(nlohmann::json::parse(stored->settings_json));
    s.source = fmt::format("the run's stored settings ({} processing {})",
                           stored->status == "inherited" ? "inherited from the recorded run by" : "of", stored->id);
  } else {
    s = defaults();
    s.geometry = resolve_geometry_config("", run_config);
    s.source = "defaults, geometry from " + s.geometry.source;
  }
  if (!overrides.empty()) s.source += ", with the command line's options";
  apply(overrides, run_dir, run_config, s);
  if (const auto problem = s.Validate(); !problem.empty()) throw std::runtime_error(problem);
  return s;
}

std::optional<SettingsOverrides> parse_processing_table(const std::string& text, const std::string& source_name) {
  const toml::table root = acquisition::parse_toml(text, source_name);
  const auto table = acquisition::TomlReader(root, "", source_name).table("processing");
  if (!table) return std::nullopt;
  const auto& r = *table;
  SettingsOverrides o;
  auto one_of = [&](std::string_view key, const std::vector<std::string>& allowed) {
    std::optional<std::string> value = r.optional_string(key);
    if (value && std::find(allowed.begin(), allowed.end(), *value) == allowed.end()) {
      std::string names;
      for (const auto& name : allowed) names += (names.empty() ? "\"" : ", \"") + name + "\"";
      r.fail(key, "expected one of " + names + ", not \"" + *value + "\"");
    }
    return value;
  };
  auto whole = [&](std::string_view key) -> std::optional<int> {
    const auto value = r.optional_integer_in(key, -1'000'000, 1'000'000);
    return value ? std::optional<int>(static_cast<int>(*value)) : std::nullopt;
  };
  if (const auto mode = one_of("mode", {"full", "probes"})) o.probes_only = *mode == "probes";
  o.method = one_of("method", {"xcorr", "flow"});
  o.flow_algorithm = one_of("flow_algorithm", fusion::flow_algorithm_names());
  o.window_px = whole("window_px");
  o.step_px = whole("step_px");
  o.passes = whole("passes");
  o.probe_context_nodes = whole("probe_context_nodes");
  o.max_shift_px = r.optional_number("max_shift_px");
  o.adaptive_refinement = r.optional_bool("adaptive_refinement");
  o.adaptive_threshold = r.optional_number("adaptive_threshold");
  if (const auto name = r.optional_string("preprocess"); name && !fusion::parse_preprocessing(*name)) {
    r.fail("preprocess", "expected one of " + fusion::preprocessing_names() + ", not \"" + *name + "\"");
  } else {
    o.preprocess = name;
  }
  if (r.has("roi_px")) {
    const std::vector<double> roi = r.numbers("roi_px");
    const bool whole_px =
        std::all_of(roi.begin(), roi.end(), [](double v) { return v == std::floor(v) && v >= 0 && v < 1e6; });
    if (roi.size() != 4 || !whole_px || roi[2] < 1 || roi[3] < 1) {
      r.fail("roi_px", "expected [x, y, width, height] in whole pixels, width and height at least 1");
    }
    o.roi_px = cv::Rect(static_cast<int>(roi[0]), static_cast<int>(roi[1]), static_cast<int>(roi[2]),
                        static_cast<int>(roi[3]));
  }
  o.mask = r.optional_string("mask");
  r.reject_unknown_keys();
  // The evaluator's own limits (a window of 8 to 128 px, 1 to 20 passes ...)
  // are checked here too, so the message points into the file.
  ProcessingSettings check = defaults();
  apply_evaluator(o, check);
  if (const auto problem = check.evaluator.Validate(); !problem.empty()) r.fail("", problem);
  return o;
}

fusion::EvaluatorOptions default_evaluator_with(const SettingsOverrides& overrides) {
  ProcessingSettings s = defaults();
  apply_evaluator(overrides, s);
  return s.evaluator;
}

ProcessingSettings resolve_runless_settings(const std::string& settings_file, const SettingsOverrides& flags) {
  if (flags.geometry_file) throw std::runtime_error("a geometry belongs to a run's processing, not to this evaluation");
  ProcessingSettings s = defaults();
  s.geometry.source.clear();
  s.source = "defaults";
  if (!settings_file.empty()) {
    std::ifstream in(settings_file);
    if (!in) throw std::runtime_error("cannot read settings file '" + settings_file + "'");
    std::ostringstream text;
    text << in.rdbuf();
    auto from_file = parse_processing_table(text.str(), settings_file);
    if (!from_file) throw std::runtime_error(settings_file + ": no [processing] table");
    if (from_file->mask && !from_file->mask->empty() && fs::path(*from_file->mask).is_relative()) {
      from_file->mask = (fs::path(settings_file).parent_path() / *from_file->mask).string();
    }
    apply_evaluator(*from_file, s);
    if (from_file->mask) s.mask = *from_file->mask;
    s.source = "[processing] of " + settings_file;
  }
  if (!flags.empty()) s.source += ", with the command line's options";
  apply_evaluator(flags, s);
  if (flags.mask) s.mask = *flags.mask;
  if (const auto problem = s.evaluator.Validate(); !problem.empty()) throw std::runtime_error(problem);
  return s;
}

std::string describe(const ProcessingSettings& s) {
  const auto& x = s.evaluator.xcorr;
  std::string text = fmt::format("{}, {}, window {} px, step {} px, {} passes, largest shift {:g} px",
                                 s.probes_only ? "probe mode" : "full fields",
                                 s.evaluator.method == fusion::Method::kOpticalFlow ? "optical flow" : "cross-correlation",
                                 x.window_px, x.step_px, x.passes, x.max_shift_px);
  if (s.probes_only) text += fmt::format(", probe context {}", x.probe_context_nodes);
  if (x.adaptive_refinement && !s.probes_only) {
    text += fmt::format(", adaptive refinement ({:g} × noise floor)", x.adaptive_threshold);
  }
  if (s.evaluator.preprocess.method != fusion::Preprocessing::kNone) {
    text += fmt::format(", preprocessing {}", fusion::to_string(s.evaluator.preprocess.method));
  }
  if (!x.roi.empty()) text += fmt::format(", ROI {},{} {}×{} px", x.roi.x, x.roi.y, x.roi.width, x.roi.height);
  text += s.mask.empty() ? ", no mask" : ", mask " + s.mask;
  if (s.geometry.source.empty()) return text;
  return text + ", geometry from " + s.geometry.source;
}

std::optional<double> stored_px_per_mm(const fs::path& run_dir) {
  std::optional<GeometryConfig> geometry;
  if (const auto stored = storage::ProcessingStore(run_dir).latest_settings()) {
    geometry = settings_from_json(nlohmann::json::parse(stored->settings_json)).geometry;
  } else {
    geometry = parse_geometry_config(storage::RunStore::open(run_dir).run().config_toml, "run config");
  }
  if (!geometry || geometry->source == "defaults") return std::nullopt;
  return fusion::BosGeometry(geometry->geometry).px_per_m_flow() * 1e-3;
}

bool inherit_settings(const fs::path& from_run, const fs::path& to_run) {
  const storage::ProcessingStore from(from_run);
  const auto stored = from.latest_settings();
  if (!stored) return false;
  const ProcessingSettings settings = settings_from_json(nlohmann::json::parse(stored->settings_json));
  if (!settings.mask.empty()) {
    const fs::path source = storage::resolve_in_run(from_run, settings.mask);
    fs::create_directories((to_run / settings.mask).parent_path());
    fs::copy_file(source, to_run / settings.mask, fs::copy_options::overwrite_existing);
  }
  // The search bound the other run's scene set is not this run's: its first frame searches again.
  std::string settings_json = stored->settings_json;
  if (auto j = nlohmann::ordered_json::parse(settings_json); j.contains("found_search")) {
    j.erase("found_search");
    settings_json = j.dump();
  }
  storage::ProcessingStore(to_run, true).add_inherited_settings(settings_json, acquisition::utc_now_ns());
  return true;
}

}  // namespace bosfuse::pipeline
