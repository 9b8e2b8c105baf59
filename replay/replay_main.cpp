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
// daemon's own writer (twin/io/detail_outputs.h).
// --key-file: batches signed with the key of --source, every STATE and REJECT verified with the
// daemon's key (messages/README.md, "Authentication"); without it anyone on the bus can forge the
// states it reports. --generate-key-file writes a new key file (mode 0600) and exits.
// Over LCM it first learns what the daemon has applied of --source (BatchSender::probe_applied):
// when that is seq > 0 it refuses to run (exit 2, naming the source, the seq and the detail)
// unless --continue (this history's batches are numbered from applied + 1: it is appended) or
// --resume (numbered from 1 as before: the applied ones are dropped as duplicates, i.e. an
// interrupted replay of the same history is finished exactly once).
// --format series: samples -> rainflow (replay/rainflow.h) -> blocks (replay/cycle_blocks.h) with
// --gate (hysteresis, N), --residue (half: ASTM E1049-85, the default; whole: each residue range
// a whole cycle, conservative; keep: the residue is dropped, not applied), --alpha-bin (rad) and
// the detail's [detail.fatigue] compressed_bonds_fatigue (fully compressive cycles mirrored or
// skipped); cycles below R = -10 are applied as the same range at R = -10.
// Output: one line per state update (human text, or JSON with --json) on stdout, then a summary
// line {"detail","cycles","broken_bonds","crack_length_m","remaining_cycles","end_of_life_cycle",
// "state_hash","engine_hash"} with --json, for a series with "skipped_cycles": {"compressive",
// "mirrored_compressive","remapped_below_floor","degenerate","nonfinite_samples"} (without
// --json these counts are one line on stderr). Exit codes: 0 done, 2 bad usage/config/history or a
// source that already has batches (without --continue/--resume), 3 runtime failure (LCM, no
// progress; a tcpq hub unreachable at start or lost during the run, named in one line).
#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <limits>

#include "messages/auth.h"
#include "messages/transport.h"
#include "replay/producer_keys.h"
#include "replay/replay_tool.h"
#include "tools/cli_checks.h"
#include "twin/io/detail_outputs.h"

namespace {
std::atomic<int> g_signal{0};
extern "C" void on_signal(int signal) { g_signal.store(signal); }
constexpr int kExitOk = 0, kExitUsage = 2, kExitRuntime = 3;
}  // namespace

int main(int argc, char** argv) {
  using namespace peritwin;
  CLI::App app{"peritwin-replay: recorded load history -> load blocks -> the twin"};
  std::string config_file, history, format = "cycles", detail_id, source_id = "replay", lcm_url;
  replay::ProducerKeyOptions keys;
  std::string generate_key_file;
  std::vector<std::string> key_ids;
  bool lockstep = false, in_process = false, json = false;
  bool append = false, resume = false;
  std::string residue = "half";
  replay::SeriesRules series_rules;
  replay::BatchingOptions batching;
  replay::ReplayOptions options;
  // Required unless --generate-key-file (checked after parsing).
  app.add_option("--config", config_file, "detail configuration (TOML), required");
  app.add_option("--history", history, "load history file, required");
  app.add_option("--format", format, "series|cycles|spectrum|lcm-log (default cycles)")
      ->check(CLI::IsMember({"series", "cycles", "spectrum", "lcm-log"}));
  app.add_option("--residue", residue,
                 "series: the rainflow residue at the end of the history: half (ASTM E1049-85, "
                 "default), whole (each range a whole cycle, conservative) or keep (not applied)")
      ->check(CLI::IsMember({"half", "whole", "keep"}));
  app.add_option("--gate", series_rules.gate,
                 "series: hysteresis gate (N); load ranges up to it are no reversals (default 0)")
      ->check(peritwin::cli::finite_in(0.0, std::numeric_limits<double>::max()));
  app.add_option("--alpha-bin", series_rules.alpha_bin,
                 "series: round each cycle's load angle to a multiple of this (rad; 0 = none)")
      ->check(peritwin::cli::finite_in(0.0, std::numeric_limits<double>::max()));
  app.add_option("--detail", detail_id, "detail id (default: the config's first detail)");
  app.add_option("--source", source_id, "source id of the batches (default replay)");
  app.add_option("--lcm-url", lcm_url, "LCM URL (default: $LCM_DEFAULT_URL, then LCM's)");
  app.add_flag("--lockstep", lockstep, "wait for the daemon to apply each batch before the next");
  auto* in_process_opt =
      app.add_flag("--in-process", in_process,
                   "run the twin library here (no LCM, no daemon; ignores --key-file)");
  std::string results_dir;
  app.add_option("--results", results_dir,
                 "with --in-process: write the daemon's results files (HDF5 + XDMF, PNGs with "
                 "[detail.output] png) to this directory")
      ->needs(in_process_opt);
  replay::add_key_options(app, keys);
  auto* generate_opt =
      app.add_option("--generate-key-file", generate_key_file,
                     "write a new key file (random keys, mode 0600, never overwrites) and exit");
  app.add_option("--key-ids", key_ids,
                 "ids of the generated keys, comma-separated (default: --source and "
                 "--daemon-key, i.e. replay,peritwin)")
      ->delimiter(',')
      ->needs(generate_opt);
  app.add_flag("--json", json, "JSON lines: one per state update, then a summary");
  app.add_option("--batch-blocks", batching.max_blocks, "blocks per batch at most (default 1024)")
      ->check(CLI::PositiveNumber);
  app.add_option("--batch-cycles", batching.max_cycles,
                 "close a batch once it holds this many cycles (default 1000)")
      ->check(CLI::PositiveNumber);
  app.add_option("--window", options.window, "batches in flight without --lockstep (256)")
      ->check(CLI::PositiveNumber);
  auto* continue_opt = app.add_flag(
      "--continue", append,
      "the daemon already has batches of --source: number this history's after them (append)");
  app.add_flag("--resume", resume,
               "the daemon already has batches of --source from this same history: number them "
               "from 1 again, the applied ones are duplicates (finish an interrupted replay)")
      ->excludes(continue_opt);
  app.add_option("--give-up-after", options.give_up_after_s,
                 "seconds without progress before failing (default 120)")
      ->check(peritwin::cli::finite_positive());
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? kExitOk : kExitUsage;
  }
  options.lockstep = lockstep;
  if (!generate_key_file.empty()) {
    if (key_ids.empty()) key_ids = {source_id, keys.daemon_key_id};
    if (const Status written = messages::write_key_file(generate_key_file, key_ids); !written) {
      std::cerr << "peritwin-replay: " << written.error().message() << "\n";
      return kExitUsage;
    }
    std::cerr << "peritwin-replay: wrote " << generate_key_file << " (mode 0600), keys:";
    for (const auto& id : key_ids) std::cerr << " " << id;
    std::cerr << "\n";
    return kExitOk;
  }
  if (config_file.empty() || history.empty()) {
    std::cerr << "peritwin-replay: " << (config_file.empty() ? "--config" : "--history")
              << " is required\nRun with --help for more information.\n";
    return kExitUsage;
  }

  // The memory bound (75 % of physical memory) only where the model is built: in-process.
  const auto loaded =
      twin::load_config(config_file, {in_process ? 0 : std::numeric_limits<std::uint64_t>::max()});
  if (!loaded.ok()) {
    std::cerr << loaded.error_text();
    return kExitUsage;
  }
  const twin::DetailConfig* detail = twin::select_detail(*loaded.config, detail_id);
  if (detail == nullptr) {
    std::cerr << "peritwin-replay: no detail \"" << detail_id << "\" in " << config_file << "\n";
    return kExitUsage;
  }
  const auto fmt = format == "series"     ? replay::InputFormat::series
                   : format == "spectrum" ? replay::InputFormat::spectrum
                   : format == "lcm-log"  ? replay::InputFormat::lcm_log
                                          : replay::InputFormat::cycles;
  series_rules.residue = residue == "whole"  ? replay::ResidueRule::whole
                         : residue == "keep" ? replay::ResidueRule::keep
                                             : replay::ResidueRule::half;
  series_rules.compressed_bonds_fatigue = detail->fatigue.compressed_bonds_fatigue;
  const auto read = replay::read_history(history, fmt, detail->id, series_rules);
  if (!read) {
    std::cerr << "peritwin-replay: " << read.error().message() << "\n";
    return kExitUsage;
  }
  const replay::HistoryBlocks& history_blocks = *read;
  if (const Status valid = replay::check_blocks(history_blocks.blocks); !valid) {
    std::cerr << "peritwin-replay: " << history << ": history " << valid.error().message()
              << " (the daemon would reject it)\n";
    return kExitUsage;
  }
  if (source_id.empty() || source_id.size() > twin::kMaxSourceIdLength) {
    std::cerr << "peritwin-replay: --source must have 1 to 64 characters\n";
    return kExitUsage;
  }
  // The keys, before anything is published: a missing one is a usage error.
  replay::ReplayAuth auth;
  if (!keys.key_file.empty() && in_process) {
    std::cerr << "peritwin-replay: --in-process publishes and receives nothing: --key-file "
                 "ignored\n";
  } else {
    auto loaded_keys = replay::load_producer_keys(keys, source_id);
    if (!loaded_keys) {
      std::cerr << "peritwin-replay: " << loaded_keys.error().message() << "\n";
      return kExitUsage;
    }
    auth = std::move(*loaded_keys);
    if (keys.sign_only) {
      std::cerr << "peritwin-replay: --sign-only: the daemon's STATE and REJECT are not "
                   "verified\n";
    }
  }
  auto batches = replay::make_twin_batches(history_blocks.blocks, detail->id, source_id, batching);
  std::int64_t cycles = 0;
  for (const auto& b : history_blocks.blocks) cycles += b.count;
  std::cerr << "peritwin-replay: " << history << ": " << history_blocks.blocks.size() << " blocks, "
            << cycles << " cycles -> " << batches.size() << " batches for " << detail->id
            << (in_process ? " (in-process)"
                : lockstep ? " (lockstep)"
                           : "")
            << "\n";
  if (!history_blocks.note.empty()) std::cerr << "peritwin-replay: " << history_blocks.note << "\n";
  if (history_blocks.conversion && !json) {
    std::cerr << "peritwin-replay: " << replay::describe_skipped(*history_blocks.conversion)
              << "\n";
  }

  std::int64_t last_seq = -2, last_life = -2;
  auto print = [&](const peritwin_msgs::damage_state_t& s) {
    if (s.state_seq == last_seq && s.remaining_life_seq == last_life) return;
    last_seq = s.state_seq;
    last_life = s.remaining_life_seq;
    std::cout << (json ? twin::state_json(s) : replay::describe(s)) << std::endl;
  };

  std::optional<peritwin_msgs::damage_state_t> final_state;
  if (in_process) {
    twin::DetailConfig run_detail = *detail;
    std::unique_ptr<twin::DetailOutputs> outputs;
    replay::TwinObserver on_twin;
    if (!results_dir.empty()) {
      run_detail.output.directory = results_dir;
      on_twin = [&outputs](const twin::Twin& t, bool last) {
        if (!outputs) {
          outputs = std::make_unique<twin::DetailOutputs>(t);
        } else if (!last) {
          outputs->record(t);
        }
        if (last) outputs->finish(t);
      };
    }
    const auto r = replay::run_in_process(run_detail, batches, print, on_twin);
    if (!r.error.empty()) {
      std::cerr << "peritwin-replay: " << r.error << "\n";
      return kExitUsage;
    }
    final_state = r.final_state;
  } else {
    if (lcm_url.empty()) {
      if (const char* env = std::getenv("LCM_DEFAULT_URL")) lcm_url = env;
    }
    // A tcpq hub is probed first: LCM would only say so on stderr, three lines per attempt.
    const auto hub = messages::tcpq_hub(lcm_url);
    if (const Status up = hub ? messages::probe_hub(*hub) : Status{}; !up) {
      std::cerr << "peritwin-replay: LCM hub " << lcm_url
                << " unreachable: " << up.error().message() << "\n";
      return kExitRuntime;
    }
    lcm::LCM lcm(lcm_url);
    if (!lcm.good() || !messages::transport_up(lcm)) {
      std::cerr << "peritwin-replay: cannot open LCM at \"" << messages::shown_url(lcm_url)
                << "\"\n";
      return kExitRuntime;
    }
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGTERM, &sa, nullptr);
    sigaction(SIGINT, &sa, nullptr);
    replay::ReplayResult r;
    bool lost = false;
    {  // ends before the summary: without a hub, LCM's unsubscribe complains on stderr
      std::int64_t applied = 0;
      {
        replay::BatchSender probe(lcm, detail->id, source_id, options, auth);
        probe.on_state(print);
        const auto learned = probe.probe_applied([] { return g_signal.load() == 0; });
        if (!learned) {
          std::cerr << "peritwin-replay: "
                    << (messages::transport_up(lcm) ? "" : "LCM hub " + lcm_url + ": ")
                    << learned.error().message() << "\n";
          return kExitRuntime;
        }
        applied = *learned;
      }
      if (applied > 0 && !append && !resume) {
        std::cerr << "peritwin-replay: source '" << source_id << "' already has batches up to seq "
                  << applied << " applied on detail " << detail->id
                  << "; use --continue to append this history after them, --resume to finish an "
                     "interrupted replay of the same history, or a new --source\n";
        return kExitUsage;
      }
      if (applied > 0 && append) {
        batches = replay::make_twin_batches(history_blocks.blocks, detail->id, source_id, batching,
                                            applied + 1);
        std::cerr << "peritwin-replay: --continue: batches numbered " << applied + 1 << " to "
                  << applied + static_cast<std::int64_t>(batches.size()) << "\n";
      } else if (applied > 0) {
        std::cerr << "peritwin-replay: --resume: seqs 1 to " << applied
                  << " are already applied, sending from " << applied + 1 << "\n";
      }
      replay::LcmReplayer replayer(lcm, std::move(batches), options, std::move(auth));
      r = replayer.run(print, [] { return g_signal.load() == 0; });
      lost = !messages::transport_up(lcm);
    }
    std::cerr << "peritwin-replay: " << r.published << " batch messages published, " << r.rewinds
              << " resend(s)\n";
    if (!r.ok) {
      std::cerr << "peritwin-replay: " << (lost ? "LCM hub " + lcm_url + ": " : "") << r.error
                << "\n";
      return kExitRuntime;
    }
    final_state = r.final_state;
  }
  if (json && final_state) {
    std::vector<messages::SummaryObject> extra;
    if (history_blocks.conversion) {
      extra.push_back({"skipped_cycles", replay::skipped_cycles(*history_blocks.conversion)});
    }
    std::cout << twin::summary_json(*final_state, extra) << std::endl;
  }
  return kExitOk;
}
