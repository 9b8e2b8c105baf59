// LCM channel names of peritwin: PERITWIN_<DETAIL>_<KIND>, e.g. "b1-ct" -> PERITWIN_B1_CT_LOAD.
// See messages/README.md for the rule and its reasons.
#pragma once

#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace peritwin::messages {

// What a channel carries (message type in parentheses).
enum class Kind {
  kLoad,         // load batches to the twin (peritwin_msgs::load_batch_t)
  kState,        // damage state after every applied batch (peritwin_msgs::damage_state_t)
  kField,        // damage field chunks, throttled (peritwin_msgs::damage_field_t)
  kReject,       // batches not applied, with the reason (peritwin_msgs::reject_t)
  kStatus,       // heartbeat (peritwin_msgs::status_t)
  kSamples,      // raw load samples for peritwin-stream (peritwin_msgs::load_samples_t), v5
  kMesh,         // the discretization, chunked (peritwin_msgs::detail_mesh_t), v6
  kMeshRequest,  // asks the daemon for the mesh again (peritwin_msgs::mesh_request_t), v6
  kObservation,  // inspections to the learning twin (peritwin_msgs::observation_t), v9
};

inline constexpr Kind kAllKinds[] = {Kind::kLoad,   Kind::kState,       Kind::kField,
                                     Kind::kReject, Kind::kStatus,      Kind::kSamples,
                                     Kind::kMesh,   Kind::kMeshRequest, Kind::kObservation};

inline constexpr std::string_view kChannelPrefix = "PERITWIN_";

// Longest detail id. LCM drops channel names longer than 63 characters
// (LCM_MAX_CHANNEL_NAME_LENGTH); 32 keeps every channel of a detail below that.
inline constexpr std::size_t kMaxDetailIdLength = 32;
inline constexpr std::size_t kMaxChannelLength = 63;

// Channel suffix of a kind: "LOAD", "STATE", "FIELD", "REJECT", "STATUS", "SAMPLES", "MESH",
// "MESH_REQUEST".
constexpr std::string_view suffix(Kind kind) {
  switch (kind) {
    case Kind::kLoad:
      return "LOAD";
    case Kind::kState:
      return "STATE";
    case Kind::kField:
      return "FIELD";
    case Kind::kReject:
      return "REJECT";
    case Kind::kStatus:
      return "STATUS";
    case Kind::kSamples:
      return "SAMPLES";
    case Kind::kMesh:
      return "MESH";
    case Kind::kMeshRequest:
      return "MESH_REQUEST";
    case Kind::kObservation:
      return "OBSERVATION";
  }
  return {};
}

// The longest suffix is MESH_REQUEST.
static_assert(kChannelPrefix.size() + kMaxDetailIdLength + 1 + suffix(Kind::kMeshRequest).size() <=
              kMaxChannelLength);
static_assert(suffix(Kind::kStatus).size() == suffix(Kind::kReject).size() &&
              suffix(Kind::kReject).size() < suffix(Kind::kSamples).size() &&
              suffix(Kind::kSamples).size() < suffix(Kind::kMeshRequest).size());

// A detail id is 1..kMaxDetailIdLength characters from [A-Za-z0-9_-].
constexpr bool is_valid_detail_id(std::string_view detail_id) noexcept {
  if (detail_id.empty() || detail_id.size() > kMaxDetailIdLength) return false;
  for (const char c : detail_id) {
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-';
    if (!ok) return false;
  }
  return true;
}

// The detail's part of a channel name: ASCII upper case, '-' -> '_' ("b1-ct" -> "B1_CT").
// The mapping is not injective ("b1-ct", "B1_CT" and "b1_Ct" share channels): detail ids of one
// deployment must have distinct tokens. Throws std::invalid_argument for an invalid detail id.
inline std::string detail_token(std::string_view detail_id) {
  if (!is_valid_detail_id(detail_id)) {
    throw std::invalid_argument("invalid detail id \"" + std::string(detail_id) + "\": need 1 to " +
                                std::to_string(kMaxDetailIdLength) +
                                " characters from [A-Za-z0-9_-]");
  }
  std::string token(detail_id);
  for (char& c : token) {
    if (c >= 'a' && c <= 'z') {
      c = static_cast<char>(c - 'a' + 'A');
    } else if (c == '-') {
      c = '_';
    }
  }
  return token;
}

// Channel of a detail and kind: "PERITWIN_" + detail_token(detail_id) + "_" + suffix(kind).
// Throws std::invalid_argument for an invalid detail id.
inline std::string channel(std::string_view detail_id, Kind kind) {
  std::string name(kChannelPrefix);
  name += detail_token(detail_id);
  name += '_';
  name += suffix(kind);
  return name;
}

// LCM subscription regex matching this kind's channel of every detail, e.g.
// "PERITWIN_[A-Z0-9_]+_LOAD" (LCM anchors subscription patterns at both ends).
inline std::string channel_regex(Kind kind) {
  std::string pattern(kChannelPrefix);
  pattern += "[A-Z0-9_]+_";
  pattern += suffix(kind);
  return pattern;
}

struct ChannelParts {
  std::string token;  // detail_token() of the detail id, e.g. "B1_CT"
  Kind kind;
};

// Inverse of channel() up to the token: "PERITWIN_B1_CT_LOAD" -> {"B1_CT", kLoad};
// std::nullopt when the name does not follow the rule.
inline std::optional<ChannelParts> parse_channel(std::string_view name) {
  if (name.size() > kMaxChannelLength || !name.starts_with(kChannelPrefix)) return std::nullopt;
  name.remove_prefix(kChannelPrefix.size());
  for (const Kind kind : kAllKinds) {
    const std::string_view tail = suffix(kind);
    if (name.size() < tail.size() + 2 || !name.ends_with(tail) ||
        name[name.size() - tail.size() - 1] != '_') {
      continue;
    }
    const std::string_view token = name.substr(0, name.size() - tail.size() - 1);
    if (!is_valid_detail_id(token) || detail_token(token) != token) return std::nullopt;
    return ChannelParts{std::string(token), kind};
  }
  return std::nullopt;
}

}  // namespace peritwin::messages
