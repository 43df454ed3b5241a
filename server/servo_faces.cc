// The servo's face contacts (server/face_contacts.h): a held pair of flat faces in the snapshot.
// Split from servo.cc by concept.

#include "server/servo.h"

namespace tangent::server {

void ServoLoop::FillFaceContacts(Snapshot* s, int* count) const {
  int n = *count;
  for (int k = 0; k < faces_.pairs() && n < kMaxContacts; ++k) {
    const int low = faces_.held(k) ? faces_.Lowest(k) : -1;
    if (low < 0) continue;
    // The global stage tracks the pair by this contact (and re-measures the pair's corners
    // itself); its force is the corners' load.
    TrackedContact& c = s->contacts[n++];
    c.surface_a = faces_.surface_f(k);
    c.surface_b = faces_.surface_g(k);
    c.body_a = scene_->surfaces[static_cast<size_t>(c.surface_a)].body;
    c.body_b = scene_->surfaces[static_cast<size_t>(c.surface_b)].body;
    Eigen::Vector4d u;
    Eigen::Vector3d p_a, p_b;
    faces_.Contact(k, low, &u, &p_a, &p_b);
    for (int i = 0; i < 4; ++i) c.u[i] = u[i];
    c.beta = faces_.corner(k, low).point.ext.distance;
    c.form = 0;
    for (int i = 0; i < 3; ++i) {
      c.p_a[i] = p_a[i];
      c.p_b[i] = p_b[i];
    }
    c.force = 0.0;
    for (int i = 0; i < FaceContacts::kCorners; ++i) c.force += FaceLoad(k, i);
  }
  *count = n;
}

}  // namespace tangent::server
