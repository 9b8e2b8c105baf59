#include "loads/producer_keys.h"

#include <utility>

#include "messages/auth.h"

namespace peritwin::loads {

core::Expected<ReplayAuth> load_producer_keys(const ProducerKeyOptions& keys,
                                              const std::string& source_id) {
  ReplayAuth auth;
  if (keys.key_file.empty()) return auth;
  const auto ring = messages::KeyRing::load(keys.key_file);
  if (!ring) return ring.error();
  for (const auto& [id, role] :
       {std::pair{source_id, "--source"}, std::pair{keys.daemon_key_id, "--daemon-key"}}) {
    if (ring->find(id) == nullptr && !(keys.sign_only && id == keys.daemon_key_id)) {
      return core::failure(keys.key_file + ": no key \"" + id + "\" (" + role + ")");
    }
  }
  auth.batch_key = *ring->find(source_id);
  if (!keys.sign_only) {
    auth.daemon_key = *ring->find(keys.daemon_key_id);
    auth.daemon_key_id = keys.daemon_key_id;
  }
  return auth;
}

}  // namespace peritwin::loads
