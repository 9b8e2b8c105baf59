#include "service/ingest.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <exception>

#include "twin/messages_io.h"

namespace peritwin::service {

core::Status Ingest::load_keys(const std::optional<config::AuthConfig>& config) {
  if (!config) {
    spdlog::warn(
        "no [auth] in the config: load batches are not authenticated and STATE/REJECT are not "
        "signed, so anyone on the bus can feed or impersonate this twin (messages/README.md, "
        "Authentication)");
    return {};
  }
  const config::AuthConfig& auth = *config;
  auto keys = messages::KeyRing::load(auth.key_file);
  if (!keys) return core::failure("[auth] key_file: " + keys.error().message());
  keys_ = std::move(*keys);
  daemon_key_ = keys_->find(auth.daemon_key);
  if (daemon_key_ == nullptr) {
    return core::failure("[auth] daemon_key: the key file " + auth.key_file + " has no key \"" +
                         auth.daemon_key + "\" to sign STATE and REJECT with");
  }
  sources_listed_ = !auth.sources.empty();
  if (!auth.sources.empty()) {
    for (const auto& source : auth.sources) {
      if (keys_->find(source) == nullptr) {
        return core::failure("[auth] sources: the key file " + auth.key_file +
                             " has no key for source \"" + source + "\"");
      }
    }
    allowed_sources_ = auth.sources;
  } else {
    // Every key but the daemon's own: a producer never needs the daemon's key.
    for (const auto& id : keys_->ids()) {
      if (id != auth.daemon_key) allowed_sources_.push_back(id);
    }
  }
  std::sort(allowed_sources_.begin(), allowed_sources_.end());
  spdlog::info("authentication on: {} source(s) allowed, STATE and REJECT signed with key \"{}\"",
               allowed_sources_.size(), auth.daemon_key);
  return {};
}

messages::Outcome Ingest::authenticate(const Received& r, const std::string& source,
                                       std::size_t signed_size,
                                       const std::vector<std::uint8_t>& tag) const {
  if (!std::binary_search(allowed_sources_.begin(), allowed_sources_.end(), source)) {
    return {messages::Verdict::auth, "source_id",
            "source \"" + source + "\" is not allowed: no key for it in the daemon's key file" +
                (sources_listed_ ? " or not in [auth] sources" : std::string())};
  }
  if (tag.empty()) {
    return {messages::Verdict::auth, "auth_tag",
            "unsigned: this daemon requires an HMAC-SHA256 tag with the key of source \"" + source +
                "\""};
  }
  if (!messages::tag_matches(*keys_->find(source), r.bytes.data(), signed_size, tag)) {
    return {messages::Verdict::auth, "auth_tag",
            "wrong tag: not signed with the key of source \"" + source + "\""};
  }
  return {};
}

Ingested Ingest::run_observation(twin::Twin& twin, const Received& r) const {
  const messages::DecodedObservation decoded =
      messages::decode_observation(r.bytes.data(), r.bytes.size());
  const auto prefixed = [](messages::Outcome o) {
    if (o.applied()) return o;
    // An observation's reject names "observation…" (reject_t.what): its producer tells it from
    // a batch's of the same source and seq.
    if (!o.what.starts_with("observation")) {
      o.what = o.what == "message" || o.what.empty() ? "observation" : "observation." + o.what;
    }
    return o;
  };
  if (!decoded.observation) {
    return {Ingested::Step::rejected, decoded.source_id, decoded.seq, decoded.nonce,
            prefixed(decoded.error)};
  }
  const messages::Observation& o = *decoded.observation;
  if (keys_) {
    if (messages::Outcome denied =
            authenticate(r, o.source_id, decoded.signed_size, decoded.auth_tag);
        !denied.applied()) {
      return {Ingested::Step::rejected, o.source_id, o.seq, o.nonce, prefixed(std::move(denied))};
    }
  }
  try {
    return {Ingested::Step::applied, o.source_id, o.seq, o.nonce, prefixed(twin.observe(o))};
  } catch (const std::exception& e) {
    return {Ingested::Step::threw,
            o.source_id,
            o.seq,
            o.nonce,
            {messages::Verdict::internal, "observation", e.what()}};
  }
}

Ingested Ingest::run(twin::Twin& twin, const Received& r) const {
  if (r.observation) return run_observation(twin, r);
  const messages::Decoded decoded = messages::decode_batch(r.bytes.data(), r.bytes.size());
  if (!decoded.batch) return {Ingested::Step::rejected, "", -1, 0, decoded.error};
  const messages::Batch& batch = *decoded.batch;
  if (keys_) {
    if (messages::Outcome denied =
            authenticate(r, batch.source_id, decoded.signed_size, decoded.auth_tag);
        !denied.applied()) {
      return {Ingested::Step::rejected, batch.source_id, batch.seq, batch.nonce, std::move(denied)};
    }
  }
  try {
    return {Ingested::Step::applied, batch.source_id, batch.seq, batch.nonce, twin.apply(batch)};
  } catch (const std::exception& e) {
    return {Ingested::Step::threw,
            batch.source_id,
            batch.seq,
            batch.nonce,
            {messages::Verdict::internal, "message", e.what()}};
  }
}

}  // namespace peritwin::service
