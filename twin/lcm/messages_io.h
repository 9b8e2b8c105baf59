// The twin's own LCM messages: the state and damage-field messages of a live Twin. The rest of
// the codec (batches, rejects, JSON lines, the receive loop) is messages/codec.h, whose names the
// twin uses through the declarations below.
#pragma once

#include <cstdint>
#include <vector>

#include "messages/codec.h"
#include "twin/model/twin.h"

namespace peritwin::twin {

using messages::applied_seq;
using messages::batch_message;
using messages::crack_length;
using messages::decode_batch;
using messages::Decoded;
using messages::handle_lcm;
using messages::kMaxBatchPayload;
using messages::now_utime;
using messages::reject_message;
using messages::state_json;
using messages::summary_json;

/// STATE of the twin's current state: cycles, bonds, cracks, K, remaining life, applied seq per
/// source, state_hash (fields: messages/README.md).
peritwin_msgs::damage_state_t state_message(const Twin& twin, std::int64_t utime);

/// The damage field of the current state in chunks of at most MAX_NODES_PER_CHUNK nodes.
std::vector<peritwin_msgs::damage_field_t> field_messages(const Twin& twin, std::int64_t utime);

}  // namespace peritwin::twin
