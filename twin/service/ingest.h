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

#include "messages/auth.h"
#include "messages/codec.h"
#include "twin/config/config.h"
#include "twin/model/twin.h"
#include "twin/service/scheduler.h"

namespace peritwin::twin {

/// What became of one received batch.
struct Ingested {
  enum class Step {
    rejected,  ///< by decode or validate: the twin is untouched
    applied,   ///< Twin::apply ran; `outcome` is its verdict (applied or not)
    threw,     ///< Twin::apply threw half-way: the model can no longer be trusted
  };
  Step step = Step::rejected;
  std::string source;     ///< the batch's source_id ("" when it did not decode)
  std::int64_t seq = -1;  ///< the batch's seq (−1 when it did not decode)
  Outcome outcome;        ///< threw: Verdict::internal with the exception's message as `why`
};

class Ingest {
 public:
  /// Loads [auth]'s key file and resolves the allowed sources; without [auth], says once that the
  /// daemon runs unauthenticated.
  Status load_keys(const std::optional<AuthConfig>& auth);
  /// The key STATE and REJECT are signed with; nullptr without [auth].
  [[nodiscard]] const messages::AuthKey* daemon_key() const { return daemon_key_; }
  /// Decodes, validates and applies one batch to `twin`.
  [[nodiscard]] Ingested run(Twin& twin, const Received& r) const;

 private:
  /// With [auth]: the batch's source is allowed and its tag is the source key's; else AUTH.
  [[nodiscard]] Outcome authenticate(const Received& r, const messages::Decoded& decoded) const;

  std::optional<messages::KeyRing> keys_;          ///< [auth] key_file; none = unauthenticated
  const messages::AuthKey* daemon_key_ = nullptr;  ///< signs STATE and REJECT
  std::vector<std::string> allowed_sources_;       ///< sorted; with keys_ only
  bool sources_listed_ = false;                    ///< [auth] sources given (not every key)
};

}  // namespace peritwin::twin
