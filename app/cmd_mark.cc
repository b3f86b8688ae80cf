// bosfuse mark: records a marker event in a run — typically "heater off"
// while the logger records it, so the run's declared origin ([run] origin =
// "heater off") is the moment it happened. Every command then counts
// experiment time from it (storage/experiment_clock.h). After the run the
// moment is given with --at (app/time_argument.h): "now" would be after
// everything recorded. With --estimate it writes nothing and proposes the
// moment from the knee of the thermocouple curves
// (pipeline/heater_off_estimate.h): the --at value on stdout, the reasoning
// on stderr.

#include <fmt/format.h>

#include <iostream>

#include "acquisition/clock.h"
#include "app/command.h"
#include "app/run_argument.h"
#include "app/time_argument.h"
#include "fitting/uncertainty_digits.h"
#include "pipeline/heater_off_estimate.h"
#include "storage/experiment_clock.h"
#include "storage/run_store.h"

namespace bosfuse::app {
namespace {

struct MarkArgs {
  std::string run;
  std::string message;
  std::string at;
  bool estimate = false;
};

// The host-clock time of --at in this run; a time from the first sample
// counts experiment seconds, so a run recorded N× fast moves by 1/N.
std::int64_t marker_time_ns(const storage::RunStore& store, const std::string& at) {
  const TimeArgument time = parse_time_argument(at);
  if (!time.from_first_sample) return time.utc_ns;
  const auto first = store.first_sample_ns();
  if (!first) throw CLI::ValidationError("--at", "the run has no sample to count " + at + " from: give a UTC time");
  return *first + static_cast<std::int64_t>(std::llround(time.offset_s / store.run().time_scale * 1e9));
}

void refuse_now_after_the_run(const storage::RunStore& store, const MarkArgs& args) {
  const storage::RunInfo run = store.run();
  if (run.status == storage::RunStatus::kRunning) return;
  throw CLI::ValidationError(
      "--at",
      fmt::format("the run is {} (ended {}): a marker made now would lie after everything it recorded. "
                  "Say when it happened: bosfuse mark {} \"{}\" --at 2026-12-01T18:11:29.5Z (UTC) or --at +12.5s "
                  "(from the first sample)",
                  storage::to_string(run.status), run.ended_ns ? storage::format_iso8601_utc(*run.ended_ns, 3) : "-",
                  args.run, args.message));
}

// Where the marker lies against what the run recorded, when outside it.
void warn_outside_the_record(const storage::RunStore& store, std::int64_t t_ns) {
  const auto first = store.first_sample_ns();
  const auto last = store.last_record_ns();
  if (first && t_ns < *first) {
    std::cerr << fmt::format("warning: the marker lies {:.3f} s (host clock) before the run's first sample\n",
                             static_cast<double>(*first - t_ns) * 1e-9);
  } else if (last && t_ns > *last) {
    std::cerr << fmt::format("warning: the marker lies {:.3f} s (host clock) after the run's last record\n",
                             static_cast<double>(t_ns - *last) * 1e-9);
  }
}

void say_what_the_origin_is(const storage::RunStore& store, const MarkArgs& args, std::int64_t t_ns) {
  if (store.run().origin_event != args.message) return;
  const std::int64_t origin = *store.marker_ns(args.message);
  if (origin == t_ns) {
    std::cerr << "this is the run's declared origin: experiment time now counts from it\n";
  } else {
    std::cerr << fmt::format(
        "the run's origin stays at the earlier \"{}\" marker ({}): the first marker of that name is t = 0\n",
        args.message, storage::format_iso8601_utc(origin, 3));
  }
}

// The proposal, for the user to accept: nothing is written.
void propose(const MarkArgs& args) {
  const auto store = storage::RunStore::open(args.run);
  const pipeline::HeaterOffEstimate estimate = pipeline::estimate_heater_off(store);
  std::cerr << estimate.brief_report();
  if (!estimate.offset_s) throw std::runtime_error("no time to propose: " + estimate.reason);
  const std::string at = "+" + fitting::format_at_uncertainty(*estimate.offset_s, estimate.sigma_s) + "s";
  std::cerr << fmt::format("nothing written; accept it with: bosfuse mark {} \"{}\" --at {}\n", args.run, args.message,
                           at);
  std::cout << at << "\n";
}

void mark(const MarkArgs& args) {
  if (args.message.empty()) throw std::runtime_error("a marker needs a name, e.g. \"heater off\"");
  if (args.estimate) return propose(args);
  auto store = storage::RunStore::open(args.run, true);
  if (args.at.empty()) refuse_now_after_the_run(store, args);
  const std::int64_t t_ns = args.at.empty() ? acquisition::utc_now_ns() : marker_time_ns(store, args.at);
  if (!args.at.empty()) warn_outside_the_record(store, t_ns);
  const storage::Event marker{0, std::nullopt, t_ns, "marker", args.message};
  store.write_events({&marker, 1});
  std::cerr << "marked \"" << args.message << "\" at " << storage::format_iso8601_utc(marker.t_ns, 3) << " in "
            << args.run << "\n";
  say_what_the_origin_is(store, args, t_ns);
}

void add_mark(CLI::App& root) {
  auto args = std::make_shared<MarkArgs>();
  CLI::App* cmd = root.add_subcommand(
      "mark",
      "Record a marker event (e.g. \"heater off\") in a run: now while a logger records it, or --at a past time");
  cmd->add_option("run", args->run, "Run folder")->required()->transform(run_folder_argument());
  cmd->add_option("message", args->message, "What happened; the run's [run] origin names the marker that is t = 0")
      ->required();
  cmd->add_option("--at", args->at,
                  "When it happened: a UTC time (2026-12-01T18:11:29.5Z) or a time from the run's first sample "
                  "with a unit (+12.5s, +250ms, +3min; experiment seconds); needed once the run has ended")
      ->check([](const std::string& text) {
        try {
          parse_time_argument(text);
          return std::string();
        } catch (const std::invalid_argument& e) {
          return std::string(e.what());
        }
      });
  cmd->add_flag("--estimate", args->estimate,
               "Write nothing: propose --at from the knee of the thermocouple curves, where heating turns into "
               "cooling (printed on stdout, the reasoning on stderr)")
      ->excludes("--at");
  cmd->callback([args] { mark(*args); });
}

BOSFUSE_COMMAND(add_mark);

}  // namespace
}  // namespace bosfuse::app
