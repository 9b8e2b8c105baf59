#include "core/program.h"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <cstdlib>

#include "core/exit_codes.h"

namespace peritwin::core {

std::optional<int> parse_options(CLI::App& app, int argc, char** argv, ParseErrors errors) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    if (errors == ParseErrors::cli11) return rc;
    return rc == 0 ? kExitOk : kExitUsage;
  }
  return std::nullopt;
}

void set_up_logging(const std::string& name, const std::string& level) {
  auto logger = spdlog::stderr_color_mt(name);
  spdlog::set_default_logger(logger);
  spdlog::set_pattern("%Y-%m-%d %H:%M:%S.%e %^%l%$ %v");
  spdlog::set_level(spdlog::level::from_str(level));
}

std::string lcm_url_or_default(std::string given) {
  if (given.empty()) {
    if (const char* env = std::getenv("LCM_DEFAULT_URL")) given = env;
  }
  return given;
}

}  // namespace peritwin::core
