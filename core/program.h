// The skeleton of the peritwin programs: option parsing with the documented exit code, the
// daemons' logging, the LCM URL default. With core/exit_codes.h, core/stop_signal.h and
// core/proc_files.h. A program's main is then
//
//   int main(int argc, char** argv) {
//     CLI::App app{"..."};
//     Options o;
//     add_options(app, o);
//     if (const auto rc = core::parse_options(app, argc, argv)) return *rc;
//     return run(o);
//   }
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>

namespace peritwin::core {

/// What a parse error (a bad or missing option, an extra argument) exits with.
enum class ParseErrors {
  usage,  ///< kExitUsage (2): the programs that document it
  cli11,  ///< CLI11's own code (CLI::ExitCodes, what CLI11_PARSE returns): the benchmarks
};

/// Parses argv into `app`. nullopt: go on. Otherwise CLI11 has printed the help (exit code 0) or
/// the error, and the value is the exit code: 0 after --help, else by `errors`.
std::optional<int> parse_options(CLI::App& app, int argc, char** argv,
                                 ParseErrors errors = ParseErrors::usage);

/// The daemons' log: spdlog's default logger on stderr (colour on a terminal) named `name`,
/// "2024-01-31 12:00:00.000 info message", at `level` (trace|debug|info|warn|error|critical|off).
void set_up_logging(const std::string& name, const std::string& level);

/// `given`, else $LCM_DEFAULT_URL, else "" (LCM's own default).
std::string lcm_url_or_default(std::string given);

}  // namespace peritwin::core
