// The global stage's clearance certificate for the servo (global_link.h).

#include "server/global_link.h"

#include <algorithm>

namespace tangent::server {

void GlobalLink::Certify(const Snapshot& snapshot) {
  certifier_.Certify(poses_, tracked_, stage_, &clearance_);
  clearances_.tick = snapshot.tick;
  clearances_.num_bodies = snapshot.num_bodies;
  for (int b = 0; b < snapshot.num_bodies; ++b) {
    std::copy(snapshot.q[b], snapshot.q[b] + 7, clearances_.q[b]);
  }
  const size_t n = std::min(clearance_.size(), static_cast<size_t>(kMaxBodyPairs));
  clearances_.num_pairs = static_cast<int32_t>(n);
  std::copy(clearance_.begin(), clearance_.begin() + static_cast<std::ptrdiff_t>(n),
            clearances_.clearance);
}

}  // namespace tangent::server
