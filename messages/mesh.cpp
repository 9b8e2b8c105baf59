#include "messages/mesh.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/fnv1a.h"
#include "messages/channels.h"

namespace peritwin::messages {
namespace {

using peritwin_msgs::detail_mesh_t;
using peritwin_msgs::mesh_polyline_t;

/// Encoded bytes of a chunk without nodes and polylines (fingerprint included).
std::size_t header_bytes(const Mesh& mesh, const std::string& hash) {
  return 8 + 8 + (4 + mesh.detail_id.size() + 1) + (4 + hash.size() + 1) + 3 * 4 + 6 * 8 + 4 + 4 +
         4;
}

std::size_t polyline_bytes(const MeshPolyline& line) { return 1 + 4 + 1 + 4 + 16 * line.x.size(); }

bool is_hex16(const std::string& s) {
  return s.size() == 16 && std::all_of(s.begin(), s.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

std::string at(const char* array, std::int32_t i) {
  return std::string(array) + "[" + std::to_string(i) + "]";
}

/// The first rule of detail_mesh_t.lcm the chunk breaks, or "".
std::string chunk_error(const detail_mesh_t& m) {
  if (!is_valid_detail_id(m.detail_id)) return "detail_id \"" + m.detail_id + "\" is not valid";
  if (!is_hex16(m.mesh_hash)) return "mesh_hash \"" + m.mesh_hash + "\" is not 16 hex digits";
  if (m.num_chunks < 1) return "num_chunks " + std::to_string(m.num_chunks) + " < 1";
  if (m.chunk_index < 0 || m.chunk_index >= m.num_chunks) {
    return "chunk_index " + std::to_string(m.chunk_index) + " not in [0, num_chunks " +
           std::to_string(m.num_chunks) + ")";
  }
  if (m.total_nodes < 1) return "total_nodes " + std::to_string(m.total_nodes) + " < 1";
  if (m.num_chunks > m.total_nodes) {
    return "num_chunks " + std::to_string(m.num_chunks) + " > total_nodes " +
           std::to_string(m.total_nodes);
  }
  for (const auto& [name, v] : {std::pair{"dx", m.dx}, std::pair{"horizon", m.horizon}}) {
    if (!std::isfinite(v) || v <= 0.0)
      return std::string(name) + " = " + std::to_string(v) + " must be > 0";
  }
  if (!std::isfinite(m.x_min) || !std::isfinite(m.x_max) || !(m.x_min < m.x_max) ||
      !std::isfinite(m.y_min) || !std::isfinite(m.y_max) || !(m.y_min < m.y_max)) {
    return "the box (x_min, y_min, x_max, y_max) is not finite and ordered";
  }
  if (m.first_node < 0 || m.num_nodes < 0 ||
      static_cast<std::int64_t>(m.first_node) + m.num_nodes > m.total_nodes) {
    return "nodes [first_node " + std::to_string(m.first_node) + ", + num_nodes " +
           std::to_string(m.num_nodes) + ") outside total_nodes " + std::to_string(m.total_nodes);
  }
  for (std::int32_t i = 0; i < m.num_nodes; ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (!std::isfinite(m.x[k])) return at("x", i) + " is not finite";
    if (!std::isfinite(m.y[k])) return at("y", i) + " is not finite";
  }
  if (m.chunk_index != 0 && m.num_polylines != 0) {
    return "num_polylines " + std::to_string(m.num_polylines) + " in chunk " +
           std::to_string(m.chunk_index) + " (chunk 0 only)";
  }
  for (std::int32_t l = 0; l < m.num_polylines; ++l) {
    const mesh_polyline_t& line = m.polylines[static_cast<std::size_t>(l)];
    const std::string name = at("polylines", l);
    if (line.kind < mesh_polyline_t::KIND_OUTLINE || line.kind > mesh_polyline_t::KIND_NOTCH) {
      return name + ".kind " + std::to_string(line.kind) + " is no KIND_*";
    }
    if (line.index < 0) return name + ".index " + std::to_string(line.index) + " < 0";
    if (line.closed != 0 && line.closed != 1) return name + ".closed is not 0 or 1";
    if (line.num_points < 2)
      return name + ".num_points " + std::to_string(line.num_points) + " < 2";
    for (std::int32_t i = 0; i < line.num_points; ++i) {
      const auto k = static_cast<std::size_t>(i);
      if (!std::isfinite(line.x[k]) || !std::isfinite(line.y[k])) {
        return name + "." + at("x", i) + " or y is not finite";
      }
    }
  }
  return {};
}

}  // namespace

std::string mesh_hash(const Mesh& mesh) {
  core::Fnv1a64 h;
  h.integer(static_cast<std::int64_t>(mesh.x.size()));
  for (const double v : {mesh.dx, mesh.horizon, mesh.x_min, mesh.y_min, mesh.x_max, mesh.y_max}) {
    h.real(v);
  }
  for (std::size_t i = 0; i < mesh.x.size(); ++i) {
    h.real(mesh.x[i]);
    h.real(i < mesh.y.size() ? mesh.y[i] : 0.0);
  }
  h.integer(static_cast<std::int64_t>(mesh.polylines.size()));
  for (const auto& line : mesh.polylines) {
    h.integer(line.kind);
    h.integer(line.index);
    h.integer(line.closed ? 1 : 0);
    h.integer(static_cast<std::int64_t>(line.x.size()));
    for (std::size_t i = 0; i < line.x.size(); ++i) {
      h.real(line.x[i]);
      h.real(line.y[i]);
    }
  }
  return core::hex64(h.get());
}

std::vector<detail_mesh_t> mesh_messages(const Mesh& mesh, std::int64_t utime) {
  if (mesh.x.empty() || mesh.x.size() != mesh.y.size()) {
    throw std::invalid_argument("mesh of \"" + mesh.detail_id +
                                "\": no node, or x and y of different sizes");
  }
  const std::string hash = mesh_hash(mesh);
  const std::size_t header = header_bytes(mesh, hash);
  std::size_t lines = 0;
  for (const auto& line : mesh.polylines) lines += polyline_bytes(line);
  if (header + lines + 16 > kMaxMeshChunkBytes) {
    throw std::invalid_argument("mesh of \"" + mesh.detail_id + "\": its polylines take " +
                                std::to_string(lines) + " bytes, more than one chunk holds");
  }
  const std::size_t total = mesh.x.size();
  // Chunk 0 holds the polylines and fewer nodes; every other chunk as many nodes as fit.
  const std::size_t first_count = std::min(total, (kMaxMeshChunkBytes - header - lines) / 16);
  const std::size_t per = (kMaxMeshChunkBytes - header) / 16;
  const std::size_t chunks = 1 + (total - first_count + per - 1) / per;
  std::vector<detail_mesh_t> out;
  std::size_t next = 0;
  for (std::size_t c = 0; c < chunks; ++c) {
    detail_mesh_t m{};
    m.utime = utime;
    m.detail_id = mesh.detail_id;
    m.mesh_hash = hash;
    m.chunk_index = static_cast<std::int32_t>(c);
    m.num_chunks = static_cast<std::int32_t>(chunks);
    m.total_nodes = static_cast<std::int32_t>(total);
    m.dx = mesh.dx;
    m.horizon = mesh.horizon;
    m.x_min = mesh.x_min;
    m.y_min = mesh.y_min;
    m.x_max = mesh.x_max;
    m.y_max = mesh.y_max;
    const std::size_t count = std::min(total - next, c == 0 ? first_count : per);
    m.first_node = static_cast<std::int32_t>(next);
    m.num_nodes = static_cast<std::int32_t>(count);
    const auto from = static_cast<std::ptrdiff_t>(next);
    const auto to = static_cast<std::ptrdiff_t>(next + count);
    m.x.assign(mesh.x.begin() + from, mesh.x.begin() + to);
    m.y.assign(mesh.y.begin() + from, mesh.y.begin() + to);
    next += count;
    if (c == 0) {
      for (const auto& line : mesh.polylines) {
        mesh_polyline_t p{};
        p.kind = line.kind;
        p.index = line.index;
        p.closed = line.closed ? 1 : 0;
        p.num_points = static_cast<std::int32_t>(line.x.size());
        p.x = line.x;
        p.y = line.y;
        m.polylines.push_back(std::move(p));
      }
    }
    m.num_polylines = static_cast<std::int32_t>(m.polylines.size());
    out.push_back(std::move(m));
  }
  return out;
}

DecodedMeshChunk decode_mesh_chunk(const void* data, std::size_t size) {
  DecodedMeshChunk out;
  if (size > kMaxMeshChunkBytes) {
    out.error = "oversized chunk: " + std::to_string(size) + " bytes > " +
                std::to_string(kMaxMeshChunkBytes);
    return out;
  }
  auto chunk = decode_mesh(data, size);
  if (!chunk) {
    out.error =
        "not a peritwin_msgs.detail_mesh_t of this version (wrong fingerprint, truncated, a count "
        "the payload cannot hold, or bytes after its end)";
    return out;
  }
  out.error = chunk_error(*chunk);
  if (out.error.empty()) out.chunk = std::move(chunk);
  return out;
}

MeshAssembler::Result MeshAssembler::add(detail_mesh_t chunk) {
  Result result;
  const auto key = std::pair{chunk.detail_id, chunk.mesh_hash};
  auto it = sets_.find(key);
  if (it == sets_.end()) {
    if (sets_.size() >= kMaxPartial) {
      sets_.erase(std::min_element(sets_.begin(), sets_.end(), [](const auto& a, const auto& b) {
        return a.second.order < b.second.order;
      }));
    }
    it = sets_.emplace(key, Set{next_order_++, {}}).first;
  }
  Set& set = it->second;
  if (!set.chunks.empty()) {
    const detail_mesh_t& first = set.chunks.begin()->second;
    if (first.num_chunks != chunk.num_chunks || first.total_nodes != chunk.total_nodes ||
        first.dx != chunk.dx || first.horizon != chunk.horizon || first.x_min != chunk.x_min ||
        first.y_min != chunk.y_min || first.x_max != chunk.x_max || first.y_max != chunk.y_max) {
      result.error = "mesh " + chunk.mesh_hash + " of \"" + chunk.detail_id + "\": chunk " +
                     std::to_string(chunk.chunk_index) +
                     " disagrees with the others (num_chunks, total_nodes, dx, horizon or box)";
      sets_.erase(it);
      return result;
    }
  }
  const std::int32_t index = chunk.chunk_index;
  set.chunks.insert_or_assign(index, std::move(chunk));
  const detail_mesh_t& any = set.chunks.begin()->second;
  if (static_cast<std::int32_t>(set.chunks.size()) < any.num_chunks) return result;

  Mesh mesh;
  mesh.detail_id = any.detail_id;
  mesh.dx = any.dx;
  mesh.horizon = any.horizon;
  mesh.x_min = any.x_min;
  mesh.y_min = any.y_min;
  mesh.x_max = any.x_max;
  mesh.y_max = any.y_max;
  // Reserved from the nodes the chunks hold, never from total_nodes: a forged chunk may claim
  // 2^31 nodes (the mesh fuzz target found an 8.5 GB reserve); the count is checked below.
  std::size_t held = 0;
  for (const auto& [i, c] : set.chunks) held += c.x.size();
  mesh.x.reserve(held);
  mesh.y.reserve(held);
  const std::string hash = any.mesh_hash;
  for (const auto& [i, c] : set.chunks) {
    if (c.first_node != static_cast<std::int32_t>(mesh.x.size())) {
      result.error = "mesh " + hash + " of \"" + mesh.detail_id + "\": chunk " + std::to_string(i) +
                     " starts at node " + std::to_string(c.first_node) + ", expected " +
                     std::to_string(mesh.x.size());
      sets_.erase(it);
      return result;
    }
    mesh.x.insert(mesh.x.end(), c.x.begin(), c.x.end());
    mesh.y.insert(mesh.y.end(), c.y.begin(), c.y.end());
    for (const auto& p : c.polylines) {
      mesh.polylines.push_back({p.kind, p.index, p.closed != 0, p.x, p.y});
    }
  }
  const auto total = static_cast<std::size_t>(any.total_nodes);
  sets_.erase(it);
  if (mesh.x.size() != total) {
    result.error = "mesh " + hash + " of \"" + mesh.detail_id + "\": its chunks hold " +
                   std::to_string(mesh.x.size()) + " nodes, total_nodes says " +
                   std::to_string(total);
    return result;
  }
  if (const std::string got = mesh_hash(mesh); got != hash) {
    result.error =
        "mesh " + hash + " of \"" + mesh.detail_id + "\": the reassembled mesh hashes to " + got;
    return result;
  }
  result.mesh = std::move(mesh);
  return result;
}

peritwin_msgs::mesh_request_t mesh_request_message(const std::string& detail_id,
                                                   const std::string& requester,
                                                   std::int64_t utime) {
  peritwin_msgs::mesh_request_t m{};
  m.utime = utime;
  m.detail_id = detail_id;
  m.requester = requester.substr(0, kMaxRequesterLength);
  return m;
}

}  // namespace peritwin::messages
