// The keys of a producer of load batches (peritwin-replay, peritwin-stream): the options
// --key-file F [--daemon-key ID | --sign-only] and their loading, one implementation for both
// tools (messages/README.md, "Authentication"). The batches are signed with the key of the
// producer's --source; every STATE and REJECT of the detail is verified with the daemon's key
// unless --sign-only.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "core/expected.h"
#include "loads/batch_sender.h"

namespace peritwin::loads {

struct ProducerKeyOptions {
  std::string key_file;  ///< empty: nothing signed or verified
  std::string daemon_key_id = "peritwin";
  bool sign_only = false;
};

/// Adds --key-file, --daemon-key and --sign-only to `app`; returns the --key-file option.
inline CLI::Option* add_key_options(CLI::App& app, ProducerKeyOptions& keys) {
  auto* key_file_opt = app.add_option(
      "--key-file", keys.key_file,
      "sign the batches with the key of --source and verify every STATE and REJECT with the "
      "daemon's (TOML [keys], mode 0600; messages/README.md). Without it nothing is signed or "
      "verified, and anyone on the bus can forge the states this tool reports");
  auto* daemon_key_opt = app.add_option("--daemon-key", keys.daemon_key_id,
                                        "id of the daemon's key in --key-file (default peritwin)")
                             ->needs(key_file_opt);
  app.add_flag("--sign-only", keys.sign_only,
               "sign the batches but verify nothing (for a producer whose key file holds only "
               "its own key; the states it reports can then be forged)")
      ->needs(key_file_opt)
      ->excludes(daemon_key_opt);
  return key_file_opt;
}

/// The keys for batches of `source_id`: empty without --key-file; an error naming the file and
/// the missing key (a usage error: nothing has been published yet).
core::Expected<ReplayAuth> load_producer_keys(const ProducerKeyOptions& keys,
                                              const std::string& source_id);

}  // namespace peritwin::loads
