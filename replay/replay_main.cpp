// peritwin-replay: feeds a recorded load history to the twin of one detail.
//
//   peritwin-replay --config detail.toml --history FILE [--format series|cycles|spectrum|lcm-log]
//                   [--detail ID] [--source ID] [--lcm-url URL] [--lockstep] [--in-process
//                   [--results DIR]] [--json] [--batch-blocks N] [--batch-cycles N] [--window N]
//                   [--residue half|whole|keep] [--gate N] [--alpha-bin RAD]
//                   [--key-file F [--daemon-key ID | --sign-only]] [--continue | --resume]
//   peritwin-replay --generate-key-file F [--key-ids ID,ID,...]
//
// Over LCM (default) it publishes the batches to a running daemon (see replay/replay_tool.h);
// --in-process runs the twin library directly with the same config (deterministic mode, no LCM);
// with --results DIR it writes the daemon's results files of the detail there (DIR instead of
// [detail.output] directory: <id>.h5, <id>.xdmf and, with output.png, the two PNGs), by the
// daemon's own writer (outputs/detail_outputs.h).
// --key-file: batches signed with the key of --source, every STATE and REJECT verified with the
// daemon's key (messages/README.md, "Authentication"); without it anyone on the bus can forge the
// states it reports. --generate-key-file writes a new key file (mode 0600) and exits.
// Over LCM it first learns what the daemon has applied of --source (BatchSender::probe_applied):
// when that is seq > 0 it refuses to run (exit 2, naming the source, the seq and the detail)
// unless --continue (this history's batches are numbered from applied + 1: it is appended) or
// --resume (an interrupted replay of the same history is finished exactly once: numbered from
// where that history started, 1 or its --continue seq, the applied ones are dropped as
// duplicates). Every batch carries the history's fingerprint (loads::history_fingerprint: its
// batches' blocks, not the ids or seqs) and first seq; the daemon keeps those of each source's
// last applied batch and publishes them in STATE, and --resume refuses (exit 2) a source whose
// last applied batch was of another history, or of none (docs/design.md, "Resuming a replay").
// --format series: samples -> rainflow (loads/rainflow.h) -> blocks (loads/cycle_blocks.h) with
// --gate (hysteresis, N), --residue (half: ASTM E1049-85, the default; whole: each residue range
// a whole cycle, conservative; keep: the residue is dropped, not applied), --alpha-bin (rad) and
// the detail's [detail.fatigue] compressed_bonds_fatigue (fully compressive cycles mirrored or
// skipped); cycles below R = -10 are applied as the same range at R = -10.
// Output: one line per state update (human text, or JSON with --json) on stdout, then a summary
// line {"detail","cycles","broken_bonds","crack_length_m","remaining_cycles","end_of_life_cycle",
// "state_hash","engine_hash"} with --json, for a series with "skipped_cycles": {"compressive",
// "mirrored_compressive","remapped_below_floor","degenerate","nonfinite_samples"} (without
// --json these counts are one line on stderr).
// Before anything is sent: a history whose peak is above the config's [detail.limits] max_p is
// refused naming the block (a units slip is likely; without max_p in the config the daemon
// derives it from the model, and only its INVALID reject can say so).
// A reject no resend can cure (loads/batch_sender.h) ends the run at once with the daemon's
// reason: INVALID, AUTH, LIMIT exit 3; FAILED after a batch of this run was applied is the end of
// life reached (the reason on stderr, exit 0), before any exit 3.
// Exit codes (core/exit_codes.h): 0 done (kExitOk), 2 (kExitUsage) bad usage/config/history, a
// history above the configured max_p, a source that already has batches (without
// --continue/--resume) or batches of another history (--resume), 3 (kExitRuntime) runtime failure
// (LCM, no progress, a batch the daemon refuses for good; a tcpq hub unreachable at start or lost
// during the run, named in one line).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <limits>

#include "core/cli_checks.h"
#include "core/exit_codes.h"
#include "core/fnv1a.h"
#include "core/program.h"
#include "core/stop_signal.h"
#include "loads/producer_keys.h"
#include "messages/auth.h"
#include "messages/transport.h"
#include "outputs/detail_outputs.h"
#include "replay/learning.h"
#include "replay/observation_sender.h"
#include "replay/replay_tool.h"
#include "twin/in_process_twin.h"

namespace {

using namespace peritwin;
using core::kExitOk;
using core::kExitRuntime;
using core::kExitUsage;

/// The command line.
struct Options {
  std::string config_file, history, format = "cycles", detail_id, source_id = "replay", lcm_url;
  loads::ProducerKeyOptions keys;
  std::string generate_key_file;
  std::vector<std::string> key_ids;
  bool lockstep = false, in_process = false, json = false;
  bool append = false, resume = false;
  std::string residue = "half";
  std::string results_dir;
  std::string observations;  ///< --observations: inspections for the learning ensemble
  loads::SeriesRules series_rules;
  loads::BatchingOptions batching;
  loads::ReplayOptions replay;
};

void add_options(CLI::App& app, Options& o) {
  // Required unless --generate-key-file (checked after parsing).
  app.add_option("--config", o.config_file, "detail configuration (TOML), required");
  app.add_option("--history", o.history, "load history file, required");
  app.add_option("--format", o.format, "series|cycles|spectrum|lcm-log (default cycles)")
      ->check(CLI::IsMember({"series", "cycles", "spectrum", "lcm-log"}));
  app.add_option("--residue", o.residue,
                 "series: the rainflow residue at the end of the history: half (ASTM E1049-85, "
                 "default), whole (each range a whole cycle, conservative) or keep (not applied)")
      ->check(CLI::IsMember({"half", "whole", "keep"}));
  app.add_option("--gate", o.series_rules.gate,
                 "series: hysteresis gate (N); load ranges up to it are no reversals (default 0)")
      ->check(peritwin::core::finite_in(0.0, std::numeric_limits<double>::max()));
  app.add_option("--alpha-bin", o.series_rules.alpha_bin,
                 "series: round each cycle's load angle to a multiple of this (rad; 0 = none)")
      ->check(peritwin::core::finite_in(0.0, std::numeric_limits<double>::max()));
  app.add_option("--detail", o.detail_id, "detail id (default: the config's first detail)");
  app.add_option("--source", o.source_id, "source id of the batches (default replay)");
  app.add_option("--lcm-url", o.lcm_url, "LCM URL (default: $LCM_DEFAULT_URL, then LCM's)");
  app.add_flag("--lockstep", o.lockstep, "wait for the daemon to apply each batch before the next");
  auto* in_process_opt =
      app.add_flag("--in-process", o.in_process,
                   "run the twin library here (no LCM, no daemon; ignores --key-file)");
  app.add_option("--results", o.results_dir,
                 "with --in-process: write the daemon's results files (HDF5 + XDMF, PNGs with "
                 "[detail.output] png) to this directory")
      ->needs(in_process_opt);
  app.add_option("--observations", o.observations,
                 "inspections (CSV: cycle,kind,origin,length_m,sigma_m,pod_a50_m,pod_slope) taken "
                 "in at their cycles by the detail's learning ensemble ([detail.uncertainty]): "
                 "in-process, or sent to the daemon on the detail's OBSERVATION channel after the "
                 "batches up to their cycle are applied");
  loads::add_key_options(app, o.keys);
  auto* generate_opt =
      app.add_option("--generate-key-file", o.generate_key_file,
                     "write a new key file (random keys, mode 0600, never overwrites) and exit");
  app.add_option("--key-ids", o.key_ids,
                 "ids of the generated keys, comma-separated (default: --source and "
                 "--daemon-key, i.e. replay,peritwin)")
      ->delimiter(',')
      ->needs(generate_opt);
  app.add_flag("--json", o.json, "JSON lines: one per state update, then a summary");
  app.add_option("--batch-blocks", o.batching.max_blocks, "blocks per batch at most (default 1024)")
      ->check(CLI::PositiveNumber);
  app.add_option("--batch-cycles", o.batching.max_cycles,
                 "close a batch once it holds this many cycles (default 1000)")
      ->check(CLI::PositiveNumber);
  app.add_option("--window", o.replay.window, "batches in flight without --lockstep (256)")
      ->check(CLI::PositiveNumber);
  auto* continue_opt = app.add_flag(
      "--continue", o.append,
      "the daemon already has batches of --source: number this history's after them (append)");
  app.add_flag("--resume", o.resume,
               "the daemon already has batches of --source from this same history: number them "
               "as before, the applied ones are duplicates (finish an interrupted replay; another "
               "history is refused)")
      ->excludes(continue_opt);
  app.add_option("--give-up-after", o.replay.give_up_after_s,
                 "seconds without progress before failing (default 120)")
      ->check(peritwin::core::finite_positive());
}

/// --generate-key-file: writes the key file and says so.
int generate_key_file(Options o) {
  if (o.key_ids.empty()) o.key_ids = {o.source_id, o.keys.daemon_key_id};
  if (const core::Status written = messages::write_key_file(o.generate_key_file, o.key_ids);
      !written) {
    std::cerr << "peritwin-replay: " << written.error().message() << "\n";
    return core::kExitUsage;
  }
  std::cerr << "peritwin-replay: wrote " << o.generate_key_file << " (mode 0600), keys:";
  for (const auto& id : o.key_ids) std::cerr << " " << id;
  std::cerr << "\n";
  return core::kExitOk;
}

/// The blocks of --history, checked by the daemon's rule; an exit code when they cannot be read
/// or are invalid.
std::optional<int> read_history(Options& o, const config::DetailConfig& detail,
                                replay::HistoryBlocks& out) {
  const auto fmt = o.format == "series"     ? replay::InputFormat::series
                   : o.format == "spectrum" ? replay::InputFormat::spectrum
                   : o.format == "lcm-log"  ? replay::InputFormat::lcm_log
                                            : replay::InputFormat::cycles;
  o.series_rules.residue = o.residue == "whole"  ? loads::ResidueRule::whole
                           : o.residue == "keep" ? loads::ResidueRule::keep
                                                 : loads::ResidueRule::half;
  o.series_rules.compressed_bonds_fatigue = detail.fatigue.mirrors_compressive_cycles();
  auto read = replay::read_history(o.history, fmt, detail.id, o.series_rules);
  if (!read) {
    std::cerr << "peritwin-replay: " << read.error().message() << "\n";
    return core::kExitUsage;
  }
  out = std::move(*read);
  if (const core::Status valid = replay::check_blocks(out.blocks); !valid) {
    std::cerr << "peritwin-replay: " << o.history << ": history " << valid.error().message()
              << " (the daemon would reject it)\n";
    return core::kExitUsage;
  }
  if (const core::Status peak = replay::check_peak(out.blocks, detail.limits); !peak) {
    std::cerr << "peritwin-replay: " << o.history << ": " << peak.error().message()
              << "; nothing sent\n";
    return core::kExitUsage;
  }
  return std::nullopt;
}

/// The keys, before anything is published: a missing one is a usage error.
std::optional<int> load_keys(const Options& o, loads::ReplayAuth& auth) {
  if (!o.keys.key_file.empty() && o.in_process) {
    std::cerr << "peritwin-replay: --in-process publishes and receives nothing: --key-file "
                 "ignored\n";
    return std::nullopt;
  }
  auto loaded_keys = loads::load_producer_keys(o.keys, o.source_id);
  if (!loaded_keys) {
    std::cerr << "peritwin-replay: " << loaded_keys.error().message() << "\n";
    return core::kExitUsage;
  }
  auth = std::move(*loaded_keys);
  if (o.keys.sign_only) {
    std::cerr << "peritwin-replay: --sign-only: the daemon's STATE and REJECT are not "
                 "verified\n";
  }
  return std::nullopt;
}

/// The history's numbers on stderr before the run.
void report_history(const Options& o, const config::DetailConfig& detail,
                    const replay::HistoryBlocks& history, std::size_t batches) {
  std::int64_t cycles = 0;
  for (const auto& b : history.blocks) cycles += b.count;
  std::cerr << "peritwin-replay: " << o.history << ": " << history.blocks.size() << " blocks, "
            << cycles << " cycles -> " << batches << " batches for " << detail.id
            << (o.in_process ? " (in-process)"
                : o.lockstep ? " (lockstep)"
                             : "")
            << "\n";
  if (!history.note.empty()) std::cerr << "peritwin-replay: " << history.note << "\n";
  if (history.conversion && !o.json) {
    std::cerr << "peritwin-replay: " << replay::describe_skipped(*history.conversion) << "\n";
  }
}

/// --results: the results files written as the in-process twin goes (DetailOutputs created at
/// the first state, a row per state, finished at the last), `detail`'s output directory set to
/// --results; no observer without --results.
twin::TwinObserver results_observer(const Options& o, config::DetailConfig& detail,
                                    std::unique_ptr<outputs::DetailOutputs>& outputs) {
  if (o.results_dir.empty()) return {};
  detail.output.directory = o.results_dir;
  return [&outputs](const twin::Twin& t, bool last) {
    if (!outputs) {
      outputs = std::make_unique<outputs::DetailOutputs>(t);
    } else if (!last) {
      outputs->record(t);
    }
    if (last) outputs->finish(t);
  };
}

/// --in-process: the batches applied here, with --results the daemon's results files written.
int replay_in_process(const Options& o, const config::DetailConfig& detail,
                      const std::vector<messages::Batch>& batches, replay::StatePrinter& printer,
                      std::optional<peritwin_msgs::damage_state_t>& final_state) {
  config::DetailConfig run_detail = detail;
  std::unique_ptr<outputs::DetailOutputs> outputs;
  const twin::TwinObserver on_twin = results_observer(o, run_detail, outputs);
  const auto r = twin::run_in_process(run_detail, batches, printer.callback(), on_twin);
  if (!r.error.empty()) {
    std::cerr << "peritwin-replay: " << r.error << "\n";
    return core::kExitUsage;
  }
  final_state = r.final_state;
  return core::kExitOk;
}

/// --resume with `applied` > 0 batches of --source applied, the last of them from the history
/// `held`: refused (exit 2) unless that is this history (the same fingerprint), whose batches are
/// then numbered from the seq it started at (1, or where a --continue appended it).
std::optional<int> check_resume(const Options& o, const config::DetailConfig& detail,
                                std::int64_t applied, const messages::SourceHistory& held,
                                const replay::HistoryBlocks& history,
                                std::vector<messages::Batch>& batches) {
  const std::uint64_t mine = batches.empty() ? 0 : batches.front().history;
  if (held.fingerprint == 0) {
    std::cerr << "peritwin-replay: --resume: source '" << o.source_id << "' has batches up to seq "
              << applied << " applied on detail " << detail.id
              << ", and the daemon holds no history fingerprint for them (they came from "
                 "peritwin-stream, from a producer before message set version 8, or from a "
                 "checkpoint written before it): nothing tells they are "
              << o.history
              << "'s; use --continue to append this history after them, or a new --source\n";
    return core::kExitUsage;
  }
  if (held.fingerprint != mine) {
    std::cerr << "peritwin-replay: --resume: source '" << o.source_id << "' has batches up to seq "
              << applied << " of another history applied on detail " << detail.id << " (history "
              << core::hex64(held.fingerprint) << " from seq " << held.start << "; " << o.history
              << " as batched here is " << core::hex64(mine)
              << "): --resume finishes an interrupted replay of the same history (the same "
                 "file, format, conversion and batching); use --continue to append this history "
                 "after them, or a new --source\n";
    return core::kExitUsage;
  }
  if (held.start != 1) {
    batches =
        loads::make_twin_batches(history.blocks, detail.id, o.source_id, o.batching, held.start);
    loads::mark_history(batches);
  }
  const std::int64_t last = held.start + static_cast<std::int64_t>(batches.size()) - 1;
  if (applied >= last) {
    std::cerr << "peritwin-replay: --resume: all " << batches.size() << " batches of " << o.history
              << " (seqs " << held.start << " to " << last << ") are applied already\n";
  } else {
    std::cerr << "peritwin-replay: --resume: seqs " << held.start << " to " << applied
              << " of this history are applied already, sending from " << applied + 1 << "\n";
  }
  return std::nullopt;
}

/// Over LCM: what the daemon has applied of --source decides the numbering (--continue,
/// --resume), then the batches are published; the final state, or an exit code.
int replay_over_lcm(const Options& o, const config::DetailConfig& detail,
                    const replay::HistoryBlocks& history, std::vector<messages::Batch> batches,
                    loads::ReplayAuth auth, replay::StatePrinter& printer,
                    std::optional<peritwin_msgs::damage_state_t>& final_state,
                    const std::vector<messages::Observation>& observations) {
  const std::string lcm_url = core::lcm_url_or_default(o.lcm_url);
  // A tcpq hub is probed first: LCM would only say so on stderr, three lines per attempt.
  const auto hub = messages::tcpq_hub(lcm_url);
  if (const core::Status up = hub ? messages::probe_hub(*hub) : core::Status{}; !up) {
    std::cerr << "peritwin-replay: LCM hub " << lcm_url << " unreachable: " << up.error().message()
              << "\n";
    return core::kExitRuntime;
  }
  lcm::LCM lcm(lcm_url);
  if (!lcm.good() || !messages::transport_up(lcm)) {
    std::cerr << "peritwin-replay: cannot open LCM at \"" << messages::shown_url(lcm_url) << "\"\n";
    return core::kExitRuntime;
  }
  core::install_stop_handler();
  replay::ReplayResult r;
  bool lost = false;
  {  // ends before the summary: without a hub, LCM's unsubscribe complains on stderr
    std::int64_t applied = 0;
    messages::SourceHistory held;  ///< the history of the source's last applied batch
    {
      loads::BatchSender probe(lcm, detail.id, o.source_id, o.replay, auth);
      probe.on_state(printer.callback());
      const auto learned = probe.probe_applied(core::keep_running);
      if (!learned) {
        std::cerr << "peritwin-replay: "
                  << (messages::transport_up(lcm) ? "" : "LCM hub " + lcm_url + ": ")
                  << learned.error().message() << "\n";
        return core::kExitRuntime;
      }
      applied = *learned;
      if (probe.last_state()) held = messages::source_history(*probe.last_state(), o.source_id);
    }
    if (applied > 0 && !o.append && !o.resume) {
      std::cerr << "peritwin-replay: source '" << o.source_id << "' already has batches up to seq "
                << applied << " applied on detail " << detail.id
                << "; use --continue to append this history after them, --resume to finish an "
                   "interrupted replay of the same history, or a new --source\n";
      return core::kExitUsage;
    }
    if (applied > 0 && o.append) {
      batches =
          loads::make_twin_batches(history.blocks, detail.id, o.source_id, o.batching, applied + 1);
      loads::mark_history(batches);
      std::cerr << "peritwin-replay: --continue: batches numbered " << applied + 1 << " to "
                << applied + static_cast<std::int64_t>(batches.size()) << "\n";
    } else if (applied > 0) {
      if (auto rc = check_resume(o, detail, applied, held, history, batches)) return *rc;
    }
    if (observations.empty()) {
      replay::LcmReplayer replayer(lcm, std::move(batches), o.replay, std::move(auth));
      r = replayer.run(printer.callback(), core::keep_running);
    } else {
      r = replay::replay_with_observations(lcm, batches, observations, o.replay, auth,
                                           printer.callback(), core::keep_running);
    }
    lost = !messages::transport_up(lcm);
  }
  std::cerr << "peritwin-replay: " << r.published << " batch messages published, " << r.rewinds
            << " resend(s)\n";
  if (r.stale_states > 0) {
    std::cerr << "peritwin-replay: " << r.stale_states
              << " STATE message(s) answering no batch of this run not taken as its progress "
                 "(another producer's, a restarted daemon's first, or old ones published again)\n";
  }
  if (!r.ok) {
    std::cerr << "peritwin-replay: " << (lost ? "LCM hub " + lcm_url + ": " : "") << r.error
              << "\n";
    return core::kExitRuntime;
  }
  if (!r.end_of_life.empty()) {
    std::cerr << "peritwin-replay: end of life reached, the rest of the history is not applied: "
              << r.end_of_life << "\n";
  }
  final_state = r.final_state;
  return core::kExitOk;
}

/// --in-process --observations: the twin and its learning ensemble (replay/learning.h).
int run_learning(const Options& o, const config::DetailConfig& detail,
                 const std::vector<messages::Batch>& split,
                 const std::vector<messages::Observation>& observations,
                 replay::StatePrinter& printer) {
  // --results: the daemon's results files, with the ensemble's rows and the observations.
  config::DetailConfig run_detail = detail;
  std::unique_ptr<outputs::DetailOutputs> outputs;
  const twin::TwinObserver on_twin = results_observer(o, run_detail, outputs);
  const auto r = replay::run_learning_in_process(
      run_detail, split, observations, o.json, printer.callback(),
      [](const std::string& line) { std::cout << line << std::endl; }, on_twin);
  if (!r.error.empty()) {
    std::cerr << "peritwin-replay: " << r.error << "\n";
    return core::kExitUsage;
  }
  if (o.json && r.final_state && r.final_estimate) {
    std::cout << replay::summary_with_ensemble(messages::summary_json(*r.final_state),
                                               *r.final_estimate)
              << std::endl;
  }
  return core::kExitOk;
}

/// The replay of `o` (after --generate-key-file and the required options); the exit code.
int run(Options o) {
  const auto loaded = replay::load_producer_config(o.config_file, o.in_process);
  if (!loaded.ok()) {
    std::cerr << loaded.error_text();
    return core::kExitUsage;
  }
  const config::DetailConfig* detail = config::select_detail(*loaded.config, o.detail_id);
  if (detail == nullptr) {
    std::cerr << "peritwin-replay: no detail \"" << o.detail_id << "\" in " << o.config_file
              << "\n";
    return core::kExitUsage;
  }
  replay::HistoryBlocks history;
  if (auto rc = read_history(o, *detail, history)) return *rc;
  if (o.source_id.empty() || o.source_id.size() > messages::kMaxSourceIdLength) {
    std::cerr << "peritwin-replay: --source must have 1 to 64 characters\n";
    return core::kExitUsage;
  }
  loads::ReplayAuth auth;
  if (auto rc = load_keys(o, auth)) return *rc;
  auto batches = loads::make_twin_batches(history.blocks, detail->id, o.source_id, o.batching);
  std::vector<messages::Observation> observations;
  if (!o.observations.empty()) {
    if (!detail->uncertainty.enabled) {
      std::cerr << "peritwin-replay: --observations: detail " << detail->id
                << " has no [detail.uncertainty] (the priors the observations update)\n";
      return core::kExitUsage;
    }
    if (o.append) {
      std::cerr << "peritwin-replay: --observations with --continue: the observations' cycles "
                   "count from the history's start; replay them with the history from its start "
                   "(--resume)\n";
      return core::kExitUsage;
    }
    auto read = loads::read_observations_csv(o.observations);
    if (!read) {
      std::cerr << "peritwin-replay: " << read.error().message() << "\n";
      return core::kExitUsage;
    }
    observations = std::move(*read);
    std::vector<std::int64_t> cycles;
    for (std::size_t i = 0; i < observations.size(); ++i) {
      messages::Observation& obs = observations[i];
      obs.detail_id = detail->id;
      obs.source_id = o.source_id;
      obs.seq = static_cast<std::int64_t>(i) + 1;
      cycles.push_back(obs.cycle);
    }
    // Each observation is taken in at its own cycle count: the batches end there.
    batches = replay::split_batches_at(batches, cycles);
    std::cerr << "peritwin-replay: " << o.observations << ": " << observations.size()
              << " observations; " << detail->uncertainty.particles << " particles\n";
  }
  loads::mark_history(batches);
  report_history(o, *detail, history, batches.size());

  replay::StatePrinter printer(o.json);
  if (!o.observations.empty() && o.in_process) {
    return run_learning(o, *detail, batches, observations, printer);
  }
  std::optional<peritwin_msgs::damage_state_t> final_state;
  const int rc = o.in_process
                     ? replay_in_process(o, *detail, batches, printer, final_state)
                     : replay_over_lcm(o, *detail, history, std::move(batches), std::move(auth),
                                       printer, final_state, observations);
  if (rc != core::kExitOk) return rc;
  if (o.json && final_state) {
    std::vector<messages::SummaryObject> extra;
    if (history.conversion) {
      extra.push_back({"skipped_cycles", replay::skipped_cycles(*history.conversion)});
    }
    std::cout << messages::summary_json(*final_state, extra) << std::endl;
  }
  return core::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"peritwin-replay: recorded load history -> load blocks -> the twin"};
  Options o;
  add_options(app, o);
  if (const auto rc = core::parse_options(app, argc, argv)) return *rc;
  o.replay.lockstep = o.lockstep;
  if (!o.generate_key_file.empty()) return generate_key_file(std::move(o));
  if (o.config_file.empty() || o.history.empty()) {
    std::cerr << "peritwin-replay: " << (o.config_file.empty() ? "--config" : "--history")
              << " is required\nRun with --help for more information.\n";
    return core::kExitUsage;
  }
  return run(std::move(o));
}
