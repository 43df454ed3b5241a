#include "server/messages.h"

namespace tangent::server {

ContactEventMsg ToEventMsg(const contact::ContactEvent& e) {
  ContactEventMsg m;
  m.added = e.kind == contact::ContactEvent::Kind::kAdded ? 1 : 0;
  m.surface_a = e.contact.a;
  m.surface_b = e.contact.b;
  for (int i = 0; i < 4; ++i) m.u[i] = e.contact.u[i];
  return m;
}

void ToGlobalInput(const Snapshot& s, std::vector<contact::BodyPose>* poses,
                   std::vector<contact::GlobalContact>* tracked) {
  poses->resize(static_cast<size_t>(s.num_bodies));
  for (int b = 0; b < s.num_bodies; ++b) {
    contact::Vector7d coordinates;
    for (int i = 0; i < 7; ++i) coordinates[i] = s.q[b][i];
    (*poses)[static_cast<size_t>(b)] = contact::BodyPose::FromCoordinates(coordinates);
  }
  tracked->clear();
  for (int k = 0; k < s.num_contacts; ++k) {
    const TrackedContact& c = s.contacts[k];
    contact::GlobalContact g;
    g.a = c.surface_a;
    g.b = c.surface_b;
    g.u = Eigen::Vector4d(c.u[0], c.u[1], c.u[2], c.u[3]);
    g.beta = c.beta;
    g.p_a = Eigen::Vector3d(c.p_a[0], c.p_a[1], c.p_a[2]);
    g.p_b = Eigen::Vector3d(c.p_b[0], c.p_b[1], c.p_b[2]);
    tracked->push_back(g);
  }
}

}  // namespace tangent::server
