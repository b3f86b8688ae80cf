// bosfuse export: a run's samples as CSV, one column per channel (--csv), its
// stored BOS probe samples with their standard uncertainties (--probes,
// report/probe_csv.h), or
// the displacement and temperature fields `bosfuse process` stored, as HDF5
// with an XDMF sidecar (--fields OUT.h5, report/field_export.h). The image
// scale for the fields' mm coordinates is --px-per-mm, else the [geometry]
// table of the run's stored experiment config, as for `bosfuse report`.
// The CSV goes to standard output unless -o names a file ("-" is standard
// output too); messages go to standard error.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <iostream>
#include <map>
#include <optional>

#include "acquisition/clock.h"
#include "app/command.h"
#include "app/output_stream.h"
#include "app/run_argument.h"
#include "pipeline/processing_settings.h"
#include "report/field_export.h"
#include "report/probe_csv.h"
#include "report/sample_csv.h"
#include "storage/experiment_clock.h"
#include "storage/run_store.h"

namespace bosfuse::app {
namespace {

struct ExportArgs {
  std::string run;
  std::string out = "-";
  bool csv = false;
  bool probes = false;
  std::string fields;
  double px_per_mm = 0;
};

// --px-per-mm, else the run's stored geometry (as for `bosfuse report`),
// else none: the grid is then in px only.
std::optional<double> image_scale(const ExportArgs& args, const storage::RunStore& store) {
  if (args.px_per_mm > 0) return args.px_per_mm;
  try {
    return pipeline::stored_px_per_mm(store.dir());
  } catch (const std::exception& e) {
    spdlog::warn("grid in px only, the run's geometry could not be read: {}", e.what());
  }
  return std::nullopt;
}

void export_fields(const ExportArgs& args, const storage::RunStore& store) {
  report::FieldExportOptions options;
  options.px_per_mm = image_scale(args, store);
  const auto result = report::export_fields(store, args.fields, options);
  spdlog::info(
      "wrote {} ({} displacement and {} temperature frames, grid in {}) and {} (open it in "
      "ParaView)",
      result.hdf5_path.string(), result.displacement_frames, result.temperature_frames,
      options.px_per_mm ? fmt::format("mm at {:g} px/mm", *options.px_per_mm) : "px", result.xdmf_path.string());
}

void add_export(CLI::App& root) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* cmd = root.add_subcommand(
      "export",
      "Export a run: its samples as CSV (one column per channel, ISO-8601 UTC time), or its processed fields as "
      "HDF5 with an XDMF sidecar");
  cmd->add_option("run", args->run, "Run folder")->required()->transform(run_folder_argument());
  auto* format = cmd->add_option_group("format", "What to export (one of)");
  auto* csv = format->add_flag("--csv", args->csv, "The samples as CSV, one column per channel");
  auto* probes = format->add_flag("--probes", args->probes,
                                  "The BOS probe samples `bosfuse process` stored as CSV, one row per probe and frame, "
                                  "with their standard uncertainties (empty where not estimated)");
  auto* fields = format->add_option(
      "--fields", args->fields,
      "The displacement and temperature fields `bosfuse process` stored, as this HDF5 file (e.g. fields.h5) plus "
      "an XDMF sidecar beside it (fields.xmf) for ParaView");
  format->require_option(1);
  cmd->add_option("--out,-o", args->out, "File to write with --csv; '-' (the default): standard output")
      ->excludes(fields);
  cmd->add_option("--px-per-mm", args->px_per_mm,
                  "Image scale for --fields, px per mm: grid coordinates in mm too (default: the run config's "
                  "[geometry], else px only)")
      ->check(CLI::PositiveNumber)
      ->excludes(csv)
      ->excludes(probes);
  cmd->callback([args] {
    // Both outputs are checked before the run is read: none is one of a run's own files.
    if (!args->fields.empty()) {
      refuse_standard_output(args->fields, "--fields", "HDF5 cannot be written to a pipe");
      check_output(args->fields, "--fields");
      check_output(report::xdmf_path_for(args->fields).string(), "--fields (its .xmf sidecar)");
    }
    check_output(args->out, "--out");
    const auto store = storage::RunStore::open(args->run);
    if (!args->fields.empty()) return export_fields(*args, store);
    OutputStream out(args->out, "--out");
    if (args->probes) {
      report::write_probe_samples_csv(store, out.stream());
    } else {
      report::write_samples_csv(store, out.stream());
    }
    out.close();
  });
}

BOSFUSE_COMMAND(add_export);

}  // namespace
}  // namespace bosfuse::app
