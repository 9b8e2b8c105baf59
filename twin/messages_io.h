// The twin's own LCM messages: the state and damage-field messages of a live Twin. The rest of
// the codec (batches, rejects, JSON lines, the receive loop) is messages/codec.h, whose names the
// twin uses through the declarations below.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "messages/codec.h"
#include "messages/mesh.h"
#include "twin/twin.h"

namespace peritwin::twin {

/// Last seq per source of the newest checkpoint on disk (damage_state_t.checkpointed_seq).
using SeqBySource = std::map<std::string, std::int64_t>;

/// STATE of the twin's current state: cycles, bonds, cracks, K, remaining life, applied seq,
/// checkpointed seq (a source missing from `checkpointed` has 0) and history per source,
/// state_hash (fields: messages/README.md). No echo (echo_source "", echo_nonce 0: the daemon
/// sets them); unsigned (tag_length 0).
peritwin_msgs::damage_state_t state_message(const Twin& twin, std::int64_t utime,
                                            const SeqBySource& checkpointed = {});

/// The damage field of the current state in chunks of at most MAX_NODES_PER_CHUNK nodes, each
/// naming the mesh (messages::mesh_hash of detail_mesh(twin.model())) whose node order it follows.
std::vector<peritwin_msgs::damage_field_t> field_messages(const Twin& twin, std::int64_t utime,
                                                          const std::string& mesh_hash);

/// Bytes of polylines a detail's mesh carries at most: lines beyond it (a polygon of thousands of
/// vertices) are left out of the drawing, never out of the nodes.
inline constexpr std::size_t kMaxMeshPolylineBytes = 40'000;

/// The mesh of a detail for detail_mesh_t: node coordinates in discretization order, dx, δ, the
/// box of the outline, and its drawing: every outline entry and hole as a closed polyline (arcs
/// and circles as chords of at most 5°), every notch as an open one.
messages::Mesh detail_mesh(const DetailModel& model);

}  // namespace peritwin::twin
