// bosfuse export: a run's samples as CSV, one column per channel.

#include <fmt/format.h>

#include <fstream>
#include <iostream>
#include <map>

#include "acquisition/clock.h"
#include "app/command.h"
#include "report/csv_cell.h"
#include "storage/run_store.h"

namespace bosfuse::app {
namespace {

// Samples sharing a timestamp (one poll of one device) share a row; a cell
// is empty where a channel has no ok sample at that time.
void write_csv(const storage::RunStore& store, std::ostream& out) {
  const auto channels = store.channels();
  std::map<std::int64_t, std::size_t> column;
  out << "time_utc,t_s";
  for (const auto& c : channels) {
    column[c.id] = column.size();
    out << "," << report::csv_text_cell(c.name + " [" + c.unit + "]");
  }
  out << "\n";
  const std::int64_t origin_ns = store.run().started_ns;
  std::vector<std::string> cells(channels.size());
  std::optional<std::int64_t> row_t;
  const auto flush_row = [&] {
    if (!row_t) return;
    out << acquisition::format_iso8601_utc(*row_t, 6) << ","
        << fmt::format("{:.6f}", static_cast<double>(*row_t - origin_ns) * 1e-9);
    for (auto& cell : cells) {
      out << "," << cell;
      cell.clear();
    }
    out << "\n";
  };
  store.for_each_sample([&](const storage::Sample& s) {
    if (row_t != s.t_ns) {
      flush_row();
      row_t = s.t_ns;
    }
    if (s.value) cells[column.at(s.channel_id)] = fmt::format("{}", *s.value);
  });
  flush_row();
}

struct ExportArgs {
  std::string run;
  std::string output;
  bool csv = false;
};

void add_export(CLI::App& root) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* cmd =
      root.add_subcommand("export", "Export a run's samples (CSV: one column per channel, ISO-8601 UTC time)");
  cmd->add_option("run", args->run, "Run folder")->required();
  cmd->add_flag("--csv", args->csv, "CSV output (the only format so far)")->required();
  cmd->add_option("--output,-o", args->output, "File to write (default: standard output)");
  cmd->callback([args] {
    const auto store = storage::RunStore::open(args->run);
    if (args->output.empty()) return write_csv(store, std::cout);
    std::ofstream out(args->output);
    if (!out) throw std::runtime_error("cannot write '" + args->output + "'");
    write_csv(store, out);
    std::cerr << "wrote " << args->output << "\n";
  });
}

BOSFUSE_COMMAND(add_export);

}  // namespace
}  // namespace bosfuse::app
