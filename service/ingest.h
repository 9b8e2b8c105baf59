// The daemon's ingest of one received batch, in three steps:
//  1. decode: the wire format, structure only (messages/codec.h); an undecodable batch is REJECT
//     CODE_DECODE with no source or seq;
//  2. validate: with [auth] (messages/README.md, "Authentication"), the batch's source is allowed
//     and the batch carries the HMAC-SHA256 tag of that source's key, else REJECT CODE_AUTH with
//     the model untouched; without [auth] every decoded batch passes;
//  3. apply: Twin::apply (order per source, duplicates and gaps, the detail's limits, the model).
// Also the keys: loaded once at start, then only read (by every detail's worker at once).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "config/config.h"
#include "messages/auth.h"
#include "messages/codec.h"
#include "service/scheduler.h"
#include "twin/twin.h"

namespace peritwin::service {

/// What became of one received batch.
struct Ingested {
  enum class Step {
    rejected,  ///< by decode or validate: the twin is untouched
    applied,   ///< Twin::apply ran; `outcome` is its verdict (applied or not)
    threw,     ///< Twin::apply threw half-way: the model can no longer be trusted
  };
  Step step = Step::rejected;
  std::string source;         ///< the batch's source_id ("" when it did not decode)
  std::int64_t seq = -1;      ///< the batch's seq (−1 when it did not decode)
  std::uint64_t nonce = 0;    ///< the batch's nonce (load_batch_t.nonce; 0 when it did not decode)
  messages::Outcome outcome;  ///< threw: Verdict::internal with the exception's message as `why`
};

class Ingest {
 public:
  /// Loads [auth]'s key file and resolves the allowed sources; without [auth], says once that the
  /// daemon runs unauthenticated.
  core::Status load_keys(const std::optional<config::AuthConfig>& auth);
  /// The key STATE and REJECT are signed with; nullptr without [auth].
  [[nodiscard]] const messages::AuthKey* daemon_key() const { return daemon_key_; }
  /// Decodes, validates and applies one batch to `twin` (an observation when r.observation).
  [[nodiscard]] Ingested run(twin::Twin& twin, const Received& r) const;

 private:
  /// The same for an observation_t: decode, authenticate, Twin::observe.
  [[nodiscard]] Ingested run_observation(twin::Twin& twin, const Received& r) const;
  /// With [auth]: the source is allowed and the message's tag over its first `signed_size` bytes
  /// is the source key's; else AUTH.
  [[nodiscard]] messages::Outcome authenticate(const Received& r, const std::string& source,
                                               std::size_t signed_size,
                                               const std::vector<std::uint8_t>& tag) const;

  std::optional<messages::KeyRing> keys_;          ///< [auth] key_file; none = unauthenticated
  const messages::AuthKey* daemon_key_ = nullptr;  ///< signs STATE and REJECT
  std::vector<std::string> allowed_sources_;       ///< sorted; with keys_ only
  bool sources_listed_ = false;                    ///< [auth] sources given (not every key)
};

}  // namespace peritwin::service
