// detail_mesh_t and mesh_request_t (message set version 6): a 60 000-node mesh is cut into chunks
// that each encode below 64 kB and reassemble into the same mesh; every chunk round-trips
// bit-exact; malformed chunks (truncated, forged counts, broken rules, chunks that disagree, a
// wrong hash) are refused with the reason.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <peritwin_msgs/damage_field_t.hpp>
#include <vector>

#include "core/fnv1a.h"
#include "messages/channels.h"
#include "messages/mesh.h"

namespace peritwin::messages {
namespace {

using peritwin_msgs::detail_mesh_t;
using peritwin_msgs::mesh_polyline_t;

template <class Message>
std::vector<std::uint8_t> encode(const Message& m) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

/// A plate of nx x ny nodes on a 0.5 mm grid with a hole (a 72-chord circle) and a notch.
messages::Mesh plate(int nx, int ny, std::string id = "b1-ct") {
  messages::Mesh m;
  m.detail_id = std::move(id);
  m.dx = 0.5e-3;
  m.horizon = 3.015 * m.dx;
  m.x_min = 0.0;
  m.y_min = 0.0;
  m.x_max = nx * m.dx;
  m.y_max = ny * m.dx;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      m.x.push_back((i + 0.5) * m.dx);
      m.y.push_back((j + 0.5) * m.dx);
    }
  }
  m.polylines.push_back(
      {mesh_polyline_t::KIND_OUTLINE, 0, true, {0, m.x_max, m.x_max, 0}, {0, 0, m.y_max, m.y_max}});
  messages::MeshPolyline hole{mesh_polyline_t::KIND_HOLE, 0, true, {}, {}};
  for (int k = 0; k < 72; ++k) {
    hole.x.push_back(0.5 * m.x_max + 0.01 * std::cos(k * 2 * M_PI / 72));
    hole.y.push_back(0.5 * m.y_max + 0.01 * std::sin(k * 2 * M_PI / 72));
  }
  m.polylines.push_back(hole);
  m.polylines.push_back({mesh_polyline_t::KIND_NOTCH, 0, false, {0, 0.02}, {0.05, 0.05}});
  return m;
}

messages::Mesh reassemble(const std::vector<detail_mesh_t>& chunks) {
  messages::MeshAssembler assembler;
  std::optional<messages::Mesh> mesh;
  for (const auto& c : chunks) {
    const auto bytes = encode(c);
    auto decoded = messages::decode_mesh_chunk(bytes.data(), bytes.size());
    EXPECT_TRUE(decoded.chunk) << decoded.error;
    if (!decoded.chunk) return {};
    auto r = assembler.add(*decoded.chunk);
    EXPECT_TRUE(r.error.empty()) << r.error;
    EXPECT_FALSE(mesh) << "completed twice";
    if (r.mesh) mesh = std::move(r.mesh);
  }
  EXPECT_TRUE(mesh);
  EXPECT_EQ(assembler.partial(), 0u);
  return mesh ? *mesh : messages::Mesh{};
}

TEST(Mesh, SixtyThousandNodesChunkBelow64kBAndReassembleEqual) {
  const messages::Mesh mesh = plate(300, 200);  // 60 000 nodes
  ASSERT_EQ(mesh.x.size(), 60000u);
  const auto chunks = messages::mesh_messages(mesh, 1'700'000'000'000'000);
  // 16 bytes a node: at least 960 000 / 60 000 chunks.
  EXPECT_GE(chunks.size(), 17u);
  std::int64_t nodes = 0;
  for (const auto& c : chunks) {
    const auto bytes = encode(c);
    EXPECT_LE(bytes.size(), messages::kMaxMeshChunkBytes) << c.chunk_index;
    EXPECT_LT(bytes.size(), 64u * 1024u) << c.chunk_index;
    EXPECT_EQ(c.num_chunks, static_cast<std::int32_t>(chunks.size()));
    EXPECT_EQ(c.first_node, nodes);
    EXPECT_EQ(c.mesh_hash, messages::mesh_hash(mesh));
    EXPECT_EQ(c.num_polylines, c.chunk_index == 0 ? 3 : 0);
    nodes += c.num_nodes;
    // Round trip: decoded equal, and re-encoded to the same bytes.
    detail_mesh_t back{};
    ASSERT_EQ(back.decode(bytes.data(), 0, static_cast<int>(bytes.size())),
              static_cast<int>(bytes.size()));
    EXPECT_EQ(encode(back), bytes);
  }
  EXPECT_EQ(nodes, 60000);
  EXPECT_EQ(reassemble(chunks), mesh);
  // Chunks out of order reassemble the same.
  auto reversed = chunks;
  std::reverse(reversed.begin(), reversed.end());
  EXPECT_EQ(reassemble(reversed), mesh);
}

TEST(Mesh, TheLongestDetailIdStillFits) {
  const messages::Mesh mesh = plate(100, 80, std::string(messages::kMaxDetailIdLength, 'z'));
  for (const auto& c : messages::mesh_messages(mesh, 0)) {
    const auto size = encode(c).size();
    EXPECT_LE(size, messages::kMaxMeshChunkBytes);
    // With its channel name: one UDP datagram of LCM 1.3.1 (65 499 bytes).
    EXPECT_LT(size + messages::channel(mesh.detail_id, messages::Kind::kMesh).size() + 1, 65'499u);
  }
  EXPECT_EQ(reassemble(messages::mesh_messages(mesh, 0)), mesh);
}

TEST(Mesh, HashChangesWithAnyCoordinate) {
  const messages::Mesh a = plate(10, 10);
  messages::Mesh b = a;
  b.x[57] = std::nextafter(b.x[57], 1.0);
  EXPECT_NE(messages::mesh_hash(a), messages::mesh_hash(b));
  messages::Mesh c = a;
  c.polylines[1].y[3] += 1e-9;
  EXPECT_NE(messages::mesh_hash(a), messages::mesh_hash(c));
  EXPECT_EQ(messages::mesh_hash(a).size(), 16u);
  c = a;
  c.detail_id = "other";  // the hash is of the mesh, not of its detail
  EXPECT_EQ(messages::mesh_hash(a), messages::mesh_hash(c));
}

TEST(Mesh, NoNodeOrOversizedPolylinesAreRefusedWhenBuilding) {
  EXPECT_THROW(messages::mesh_messages(messages::Mesh{}, 0), std::invalid_argument);
  messages::Mesh m = plate(4, 4);
  messages::MeshPolyline huge{mesh_polyline_t::KIND_OUTLINE, 1, true, {}, {}};
  huge.x.assign(4000, 0.0);
  huge.y.assign(4000, 0.0);
  m.polylines.push_back(huge);
  EXPECT_THROW(messages::mesh_messages(m, 0), std::invalid_argument);
}

/// The error decode_mesh_chunk gives for the chunk after `edit`.
std::string error_after(const std::function<void(detail_mesh_t&)>& edit) {
  auto chunks = messages::mesh_messages(plate(20, 10), 0);
  detail_mesh_t c = chunks[0];
  edit(c);
  const auto bytes = encode(c);
  const auto decoded = messages::decode_mesh_chunk(bytes.data(), bytes.size());
  EXPECT_EQ(decoded.chunk.has_value(), decoded.error.empty());
  return decoded.error;
}

TEST(Mesh, MalformedChunksAreRefusedWithTheReason) {
  EXPECT_EQ(error_after([](detail_mesh_t&) {}), "");
  EXPECT_NE(error_after([](detail_mesh_t& c) { c.chunk_index = 1; }).find("chunk_index 1"),
            std::string::npos);
  EXPECT_NE(error_after([](detail_mesh_t& c) { c.num_chunks = 0; }).find("num_chunks"),
            std::string::npos);
  EXPECT_NE(error_after([](detail_mesh_t& c) {
              c.x[7] = std::numeric_limits<double>::quiet_NaN();
            }).find("x[7] is not finite"),
            std::string::npos);
  EXPECT_NE(error_after([](detail_mesh_t& c) { c.dx = 0; }).find("dx"), std::string::npos);
  EXPECT_NE(error_after([](detail_mesh_t& c) { c.total_nodes = 5; }).find("outside total_nodes"),
            std::string::npos);
  EXPECT_NE(error_after([](detail_mesh_t& c) { c.mesh_hash = "xyz"; }).find("mesh_hash"),
            std::string::npos);
  EXPECT_NE(error_after([](detail_mesh_t& c) { c.detail_id = "b1.ct"; }).find("detail_id"),
            std::string::npos);
  EXPECT_NE(
      error_after([](detail_mesh_t& c) { c.polylines[0].kind = 9; }).find("polylines[0].kind"),
      std::string::npos);
  EXPECT_NE(error_after([](detail_mesh_t& c) {
              c.polylines[2].x.resize(1);
              c.polylines[2].y.resize(1);
              c.polylines[2].num_points = 1;
            }).find("polylines[2].num_points 1"),
            std::string::npos);
  EXPECT_NE(error_after([](detail_mesh_t& c) { c.y_max = c.y_min; }).find("box"),
            std::string::npos);
}

TEST(Mesh, TruncatedForgedOrForeignBytesAreRefused) {
  const auto bytes = encode(messages::mesh_messages(plate(20, 10), 0)[0]);
  for (std::size_t len = 0; len < bytes.size(); len += (len < 200 ? 1 : 97)) {
    EXPECT_FALSE(messages::decode_mesh_chunk(bytes.data(), len).chunk) << len;
  }
  auto longer = bytes;
  longer.push_back(0);
  EXPECT_NE(messages::decode_mesh_chunk(longer.data(), longer.size()).error.find("bytes after"),
            std::string::npos);
  // A forged num_nodes of 2^30 (at its offset: after the fixed header) cannot allocate.
  auto forged = bytes;
  const std::size_t at = 8 + 8 + (4 + 6) + (4 + 17) + 3 * 4 + 6 * 8 + 4;
  ASSERT_LT(at + 4, forged.size());
  forged[at] = 0x40;
  forged[at + 1] = forged[at + 2] = forged[at + 3] = 0;
  EXPECT_FALSE(messages::decode_mesh_chunk(forged.data(), forged.size()).chunk);
  // Another type's bytes: a wrong fingerprint.
  peritwin_msgs::damage_field_t field{};
  field.detail_id = "b1-ct";
  const auto other = encode(field);
  EXPECT_NE(messages::decode_mesh_chunk(other.data(), other.size()).error.find("fingerprint"),
            std::string::npos);
  // Above the size limit.
  std::vector<std::uint8_t> big(messages::kMaxMeshChunkBytes + 1, 0);
  EXPECT_NE(messages::decode_mesh_chunk(big.data(), big.size()).error.find("oversized"),
            std::string::npos);
}

TEST(Mesh, AssemblerDropsChunksThatDisagreeOrDoNotMatchTheirHash) {
  const messages::Mesh mesh = plate(200, 100);
  auto chunks = messages::mesh_messages(mesh, 0);
  ASSERT_GE(chunks.size(), 3u);
  {
    messages::MeshAssembler a;
    EXPECT_TRUE(a.add(chunks[0]).error.empty());
    auto bad = chunks[1];
    bad.total_nodes += 1;
    EXPECT_NE(a.add(bad).error.find("disagrees"), std::string::npos);
    EXPECT_EQ(a.partial(), 0u);
  }
  {
    messages::MeshAssembler a;
    auto tampered = chunks;
    tampered[1].x[3] += 1e-3;  // same hash claimed, other coordinates
    messages::MeshAssembler::Result last;
    for (const auto& c : tampered) last = a.add(c);
    EXPECT_FALSE(last.mesh);
    EXPECT_NE(last.error.find("hashes to"), std::string::npos) << last.error;
  }
  {
    messages::MeshAssembler a;
    auto shifted = chunks;
    shifted[1].first_node += 1;
    messages::MeshAssembler::Result last;
    for (const auto& c : shifted) last = a.add(c);
    EXPECT_FALSE(last.mesh);
    EXPECT_NE(last.error.find("starts at node"), std::string::npos) << last.error;
  }
  {
    // Incomplete sets are bounded.
    messages::MeshAssembler a;
    for (int k = 0; k < 20; ++k) {
      auto c = chunks[0];
      c.mesh_hash = core::hex64(static_cast<std::uint64_t>(k));
      a.add(c);
    }
    EXPECT_EQ(a.partial(), messages::MeshAssembler::kMaxPartial);
  }
}

TEST(Mesh, RequestRoundTripAndMalformedRequests) {
  const auto request = messages::mesh_request_message("b1-ct", "peritwin-dashboard", 42);
  const auto bytes = encode(request);
  const auto back = messages::decode_mesh_request(bytes.data(), bytes.size());
  ASSERT_TRUE(back);
  EXPECT_EQ(back->detail_id, "b1-ct");
  EXPECT_EQ(back->requester, "peritwin-dashboard");
  EXPECT_EQ(back->utime, 42);
  for (std::size_t len = 0; len < bytes.size(); ++len) {
    EXPECT_FALSE(messages::decode_mesh_request(bytes.data(), len)) << len;
  }
  auto bad_id = request;
  bad_id.detail_id = "b1 ct";
  const auto b = encode(bad_id);
  EXPECT_FALSE(messages::decode_mesh_request(b.data(), b.size()));
  auto long_requester = request;
  long_requester.requester = std::string(messages::kMaxRequesterLength + 1, 'r');
  const auto l = encode(long_requester);
  EXPECT_FALSE(messages::decode_mesh_request(l.data(), l.size()));
  EXPECT_EQ(messages::mesh_request_message("b1-ct", std::string(100, 'r'), 0).requester.size(),
            messages::kMaxRequesterLength);
}

}  // namespace
}  // namespace peritwin::messages
