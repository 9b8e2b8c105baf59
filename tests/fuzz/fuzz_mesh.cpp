// Fuzz target: a detail_mesh_t or mesh_request_t payload as it comes off the bus (the dashboard's
// and the daemon's view) -> decode_mesh_chunk, MeshAssembler, decode_mesh_request. Properties:
// decoding never reads or allocates beyond the payload (ASan); a chunk is either decoded or refused
// with a reason, never both; an accepted chunk re-encodes to the same bytes; a mesh the assembler
// completes hashes to the chunk's mesh_hash.
#include <vector>

#include "messages/mesh.h"
#include "tests/fuzz/fuzz_target.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace peritwin::messages;
  using peritwin::fuzz::require;
  auto decoded = decode_mesh_chunk(data, size);
  require(decoded.chunk.has_value() == decoded.error.empty(), "a chunk or a reason, not both");
  if (decoded.chunk) {
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(decoded.chunk->getEncodedSize()));
    decoded.chunk->encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    require(bytes == std::vector<std::uint8_t>(data, data + size), "a chunk re-encodes the same");
    const std::string hash = decoded.chunk->mesh_hash;
    MeshAssembler assembler;
    const auto result = assembler.add(std::move(*decoded.chunk));
    if (result.mesh) require(mesh_hash(*result.mesh) == hash, "a completed mesh has its hash");
  }
  (void)decode_mesh_request(data, size);
  return 0;
}
