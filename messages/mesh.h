// The mesh of a detail on the bus (detail_mesh_t, mesh_request_t; message set version 6): what a
// subscriber needs to draw damage_field_t messages without the daemon's files. Building the chunks
// (every encoded chunk at most detail_mesh_t::MAX_ENCODED_SIZE bytes), checking a chunk received
// from the bus (layout first, then every rule, with the reason), and reassembling the chunks into
// the mesh, checked against its hash. No model here: the twin builds its Mesh in
// twin/messages_io.h.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <peritwin_msgs/detail_mesh_t.hpp>
#include <peritwin_msgs/mesh_request_t.hpp>
#include <string>
#include <utility>
#include <vector>

namespace peritwin::messages {

/// Largest encoded detail_mesh_t chunk (bytes).
inline constexpr std::size_t kMaxMeshChunkBytes =
    static_cast<std::size_t>(peritwin_msgs::detail_mesh_t::MAX_ENCODED_SIZE);
/// Largest mesh_request_t::requester (characters).
inline constexpr std::size_t kMaxRequesterLength = 64;

/// One line of the drawing (mesh_polyline_t): kind KIND_OUTLINE / KIND_HOLE / KIND_NOTCH.
struct MeshPolyline {
  std::int8_t kind = peritwin_msgs::mesh_polyline_t::KIND_OUTLINE;
  std::int32_t index = 0;
  bool closed = true;
  std::vector<double> x, y;  ///< m, >= 2 points
  bool operator==(const MeshPolyline&) const = default;
};

/// A detail's mesh as a whole (all chunks together).
struct Mesh {
  std::string detail_id;
  double dx = 0.0;                                            ///< grid spacing (m)
  double horizon = 0.0;                                       ///< δ (m)
  double x_min = 0.0, y_min = 0.0, x_max = 0.0, y_max = 0.0;  ///< box of the outline (m)
  std::vector<double> x, y;                                   ///< node coordinates (m)
  std::vector<MeshPolyline> polylines;
  bool operator==(const Mesh&) const = default;
};

/// 16 lower-case hex digits: FNV-1a 64 over everything of the mesh but its detail id (the node
/// count, dx, horizon, box, coordinates and polylines, bit for bit).
std::string mesh_hash(const Mesh& mesh);

/// The chunks of a mesh (its hash in each): nodes in order, as many per chunk as fit in
/// kMaxMeshChunkBytes, the polylines in chunk 0. Throws std::invalid_argument when the mesh has
/// no node, or its polylines alone do not fit in one chunk.
std::vector<peritwin_msgs::detail_mesh_t> mesh_messages(const Mesh& mesh, std::int64_t utime);

/// A chunk decoded from untrusted bytes, layout checked only (every count and string against the
/// payload, nothing after the end), or nullopt. decode_mesh_chunk adds the rules.
std::optional<peritwin_msgs::detail_mesh_t> decode_mesh(const void* data, std::size_t size);

/// A chunk decoded from untrusted bytes and checked against every rule of detail_mesh_t.lcm, or
/// the reason it is refused ("wrong fingerprint ...", "chunk_index 3 not below num_chunks 2",
/// "x[17] is not finite", ...).
struct DecodedMeshChunk {
  std::optional<peritwin_msgs::detail_mesh_t> chunk;
  std::string error;
};
DecodedMeshChunk decode_mesh_chunk(const void* data, std::size_t size);

/// Reassembles chunks into meshes, per (detail_id, mesh_hash); checked chunks only
/// (decode_mesh_chunk). A set whose chunks disagree (num_chunks, total_nodes, dx, ...) or do not
/// tile the nodes, or whose reassembled mesh has another hash, is dropped with the reason. At most
/// kMaxPartial incomplete sets are kept (the oldest goes first).
class MeshAssembler {
 public:
  static constexpr std::size_t kMaxPartial = 8;
  struct Result {
    std::optional<Mesh> mesh;  ///< set when this chunk completed its mesh
    std::string error;         ///< set when this chunk's set was dropped
  };
  Result add(peritwin_msgs::detail_mesh_t chunk);
  [[nodiscard]] std::size_t partial() const { return sets_.size(); }

 private:
  struct Set {
    std::uint64_t order = 0;
    std::map<std::int32_t, peritwin_msgs::detail_mesh_t> chunks;
  };
  std::map<std::pair<std::string, std::string>, Set> sets_;
  std::uint64_t next_order_ = 0;
};

/// A mesh request decoded from untrusted bytes (layout checked, requester at most
/// kMaxRequesterLength characters, detail_id valid), or nullopt.
std::optional<peritwin_msgs::mesh_request_t> decode_mesh_request(const void* data,
                                                                 std::size_t size);
peritwin_msgs::mesh_request_t mesh_request_message(const std::string& detail_id,
                                                   const std::string& requester,
                                                   std::int64_t utime);

}  // namespace peritwin::messages
