#include "server/servo.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include <Eigen/Geometry>

#include "contact/rigid.h"
#include "nurbs/flat.h"
#include "optimizer/joints.h"
#include "optimizer/trims.h"

namespace tangent::server {

namespace {

// The mechanism the servo models: the scene's, with every body nothing acts on (no joint, no
// declared contact pair, not grasped, in no objective) held fixed at its pose. Such a body can
// never move, so it gets no coordinates, no metric block and no solver work: a scene that
// declares twenty parts but lets three touch costs what the three cost (docs/server.md, "Model
// only what a scene needs").
optimizer::Mechanism ModelledMechanism(const Scene& scene) {
  const optimizer::Mechanism& m = scene.mechanism;
  std::vector<char> acted(static_cast<size_t>(m.num_bodies()), 0);
  auto mark = [&](int body) {
    if (body >= 0) acted[static_cast<size_t>(body)] = 1;
  };
  auto mark_term = [&](const optimizer::TermPtr& t) {
    if (t) {
      mark(t->body_a());
      mark(t->body_b());
    }
  };
  for (const JointSpec& j : scene.joints) {
    mark_term(j.term);
    mark_term(j.limits);
  }
  for (const ContactPairSpec& pair : scene.pairs) {
    mark(scene.surfaces[static_cast<size_t>(pair.surface_a)].body);
    mark(scene.surfaces[static_cast<size_t>(pair.surface_b)].body);
  }
  for (const BodyPairSpec& pair : scene.body_pairs) {
    mark(pair.body_a);
    mark(pair.body_b);
  }
  mark(scene.grasp.body);
  for (const ObjectiveSpec& o : scene.objectives) mark_term(o.term);
  optimizer::Mechanism modelled;
  for (int i = 0; i < m.num_bodies(); ++i) {
    optimizer::Body b = m.body(i);
    b.fixed = b.fixed || !acted[static_cast<size_t>(i)];
    modelled.AddBody(b);
  }
  return modelled;
}

}  // namespace

ServoLoop::ServoLoop(const Scene& scene_in, const ServoOptions& options)
    : scene_(&scene_in), options_(options), lines_(options.line) {
  const Scene* scene = scene_;
  if (options.dof != 3 && options.dof != 6) {
    throw SceneError("device: dof must be 3 or 6, got " + std::to_string(options.dof));
  }
  if (scene->mechanism.num_bodies() > kMaxBodies) {
    throw SceneError(scene->path + ": more than " + std::to_string(kMaxBodies) + " bodies");
  }
  problem_ = std::make_unique<optimizer::Problem>(ModelledMechanism(*scene));
  optimizer::Problem& p = *problem_;
  p.set_least_astonishment(scene->least_astonishment);
  for (const JointSpec& j : scene->joints) {
    p.AddEquality(j.term);
    if (j.limits) p.AddInequality(j.limits);
  }
  q_ = p.mechanism().InitialCoordinates();
  p.mechanism().Poses(q_, &poses_);

  int slot_count = 0;
  for (const ContactPairSpec& pair : scene->pairs) slot_count += pair.max_contacts;
  for (const BodyPairSpec& pair : scene->body_pairs) slot_count += pair.max_contacts;
  if (slot_count > kMaxContacts) {
    throw SceneError(scene->path + ": the contact pairs reserve " + std::to_string(slot_count) +
                     " contact slots, more than " + std::to_string(kMaxContacts));
  }
  // Contacts present at the initial poses: one cold global pass (kept for the first clearance
  // certificate, StartClearanceGuard).
  std::vector<contact::ContactEvent> events;
  contact::GlobalContactStage stage(GlobalSurfaces(), GlobalPairs(), GlobalBodyPairs(),
                                    GlobalStageOptions());
  stage.Run(poses_, {}, &events);
  const std::vector<contact::BodyPose> pass_poses = poses_;
  for (const ContactPairSpec& pair : scene->pairs) {
    const SceneSurface& sa = scene->surfaces[static_cast<size_t>(pair.surface_a)];
    const SceneSurface& sb = scene->surfaces[static_cast<size_t>(pair.surface_b)];
    const int lo = std::min(pair.surface_a, pair.surface_b);
    const int hi = std::max(pair.surface_a, pair.surface_b);
    const SceneSurface& f = scene->surfaces[static_cast<size_t>(lo)];
    const SceneSurface& g = scene->surfaces[static_cast<size_t>(hi)];
    if (pair.kind == ContactPairSpec::Kind::kFloating) {
      const contact::ContactEvent* found = nullptr;
      for (const auto& e : events) {
        if (e.contact.a == lo && e.contact.b == hi && e.kind == contact::ContactEvent::Kind::kAdded)
          found = &e;
      }
      Eigen::Vector4d seed;
      if (found) {
        seed = found->contact.u;
      } else {
        // Not touching yet: the closest pair of samples, if near enough for the settling solve
        // to bring the surfaces together.
        double d = 0.0;
        seed = contact::ClosestSamplePair(f.surface, poses_[static_cast<size_t>(f.body)], g.surface,
                                          poses_[static_cast<size_t>(g.body)], 40, &d);
        if (d > 5e-3) {
          throw SceneError(scene->path + ": floating contact between \"" + sa.name + "\" and \"" +
                           sb.name + "\": the surfaces are " + std::to_string(d * 1e3) +
                           " mm apart at the initial poses (at most 5 mm)");
        }
      }
      auto term = optimizer::MakeSurfaceContact(f.body, &f.surface, g.body, &g.surface, seed,
                                                options.tracking);
      p.AddEquality(term);
      slots_.push_back({lo, hi, -1, true, false, term});
      continue;
    }
    if (options.face_contacts && !f.trim && !g.trim) {
      // Two flat faces: held by their corners (face_contacts.h), no extremal slots.
      const std::optional<nurbs::FlatQuad> qf = nurbs::FlatQuadOf(f.surface);
      const std::optional<nurbs::FlatQuad> qg = nurbs::FlatQuadOf(g.surface);
      if (qf && qg) {
        faces_.AddPair(&p, lo, f.body, &f.surface, *qf, hi, g.body, &g.surface, *qg);
        continue;
      }
    }
    const int line = options.line_contacts && !f.trim && !g.trim
                         ? lines_.AddPair(&p, f.body, &f.surface, g.body, &g.surface)
                         : -1;
    for (int m = 0; m < pair.max_contacts; ++m) {
      // On a trimmed pair the contact measures only the material (a trimmed surface as the
      // term's f; with both trimmed, both materials, edge against edge too: docs/trimming.md).
      Slot slot{lo, hi, 0, false, false, nullptr};
      const Eigen::Vector4d seed = Eigen::Vector4d::Constant(0.5);
      if (f.trim) {
        slot.term = std::make_shared<optimizer::TrimmedContactTerm>(
            f.body, &f.surface, &*f.trim, g.body, &g.surface, seed, options.tracking,
            g.trim ? &*g.trim : nullptr);
      } else if (g.trim) {
        slot.swapped = true;
        slot.term = std::make_shared<optimizer::TrimmedContactTerm>(
            g.body, &g.surface, &*g.trim, f.body, &f.surface, seed, options.tracking);
      } else {
        slot.term = optimizer::MakeSurfaceContact(f.body, &f.surface, g.body, &g.surface, seed,
                                                  options.tracking);
        slot.plain = true;
      }
      slot.line = line;
      const int index = p.AddInequality(slot.term);  // deactivated below, once solver_ has data
      slot.row = p.inequalities()[static_cast<size_t>(index)].row;
      slots_.push_back(std::move(slot));
    }
  }
  // Body pairs: a pool of slots each, every slot one term over both bodies' face tables (a
  // face's trim edges built once, shared by its pools). Memory: the faces and the slots.
  std::vector<std::optional<optimizer::ContactFace>> faces(scene->surfaces.size());
  auto faces_of = [&](int body) {
    std::vector<optimizer::ContactFace> out;
    for (size_t i = 0; i < scene->surfaces.size(); ++i) {
      const SceneSurface& sf = scene->surfaces[i];
      if (sf.body != body) continue;
      if (!faces[i]) {
        faces[i] = optimizer::MakeContactFace(static_cast<int>(i), sf.body, &sf.surface,
                                              sf.trim ? &*sf.trim : nullptr);
      }
      out.push_back(*faces[i]);
    }
    return out;
  };
  for (size_t k = 0; k < scene->body_pairs.size(); ++k) {
    const BodyPairSpec& pair = scene->body_pairs[k];
    for (int m = 0; m < pair.max_contacts; ++m) {
      auto term = optimizer::MakeBodyContact(faces_of(pair.body_a), faces_of(pair.body_b),
                                             options.tracking);
      Slot slot{-1, -1, 0, false, false, term};
      slot.body_pair = static_cast<int>(k);
      slot.body_term = term.get();
      const int index = p.AddInequality(slot.term);
      slot.row = p.inequalities()[static_cast<size_t>(index)].row;
      slots_.push_back(std::move(slot));
    }
  }

  // The grasp: a position goal at the grasp point (its weight is the coupling stiffness, in
  // the units where least astonishment has the problem's default weight), and for 6-DOF an
  // orientation goal with the rotational stiffness relative to the translational one.
  grasp_at_ = optimizer::Attachment{scene->grasp.body, scene->grasp.point};
  const contact::BodyPose& gp = poses_[static_cast<size_t>(scene->grasp.body)];
  grasp_ = optimizer::MakePositionGoal(grasp_at_, gp.Point(scene->grasp.point));
  p.AddObjective(grasp_, 1.0);
  if (options.dof == 6) {
    grasp_orientation_ =
        optimizer::MakeOrientationGoal(scene->grasp.body, gp.R_WB, Eigen::Vector3d::Ones());
    // E = ½ k_r Σ|R e_i − R_t e_i|² ≈ k_r θ²: weight k_rot / 2 relative to the grasp's k.
    p.AddObjective(grasp_orientation_,
                   0.5 * scene->grasp.rotational_stiffness / scene->device.stiffness);
  } else if (scene->grasp.hold_orientation > 0.0) {
    p.AddObjective(optimizer::OrientationGoal(scene->grasp.body, gp.R_WB, Eigen::Vector3d::Ones()),
                   scene->grasp.hold_orientation);
  }
  for (const ObjectiveSpec& o : scene->objectives) p.AddObjective(o.term, o.weight);
  optimizer::SolverOptions so;
  so.max_iterations = options.max_iterations;
  so.step_reach = options.step_reach;
  so.bounded_normal_step = options.bounded_normal_step;
  so.indefinite_floor = options.indefinite_floor;
  so.kkt_tolerance = options.kkt_tolerance;
  solver_ = std::make_unique<optimizer::Solver>(p, so);
  // The per-solve data the tick changes: contact slots (free ones deactivated, then the cold
  // global pass's contacts), the grasp targets.
  for (Slot& s : slots_) {
    s.state = &solver_->data().StateAs<optimizer::ContactSlotState>(*s.term);
    if (s.body_term)
      s.body_state = &solver_->data().StateAs<optimizer::BodyContactTerm::State>(*s.term);
    if (!s.floating) s.state->Deactivate();
  }
  lines_.Bind(solver_.get());
  faces_.Bind(solver_.get());
  for (const auto& e : events) Apply(ToEventMsg(e));  // (a cold pass only adds)
  grasp_state_ = &solver_->data().Of(*grasp_);
  if (grasp_orientation_) grasp_orientation_state_ = &solver_->data().Of(*grasp_orientation_);
  // Settle the initial configuration exactly (contacts at machine precision before the hand):
  // a longer budget, then fresh multipliers for the servo's own options.
  optimizer::SolverOptions settle = so;
  settle.max_iterations = 60;
  solver_->set_options(settle);
  solver_->Solve(&q_);
  solver_->Reset();
  solver_->set_options(so);
  solver_->Solve(&q_);
  p.mechanism().Poses(q_, &poses_);
  StartClearanceGuard(stage, pass_poses);
  device_origin_ = scene->device.origin_given ? scene->device.origin : GraspPoint();
  target_ = GraspPoint();
  grasp_state_->target = target_;
  orientation_target_ = Eigen::Quaterniond(poses_[static_cast<size_t>(grasp_at_.body)].R_WB);
  if (grasp_orientation_state_)
    grasp_orientation_state_->R_target = orientation_target_.toRotationMatrix();
  q_good_ = q_;
  lambda_e_good_ = solver_->equality_multipliers();
  lambda_i_good_ = solver_->inequality_multipliers();
  KeepGood();
}

ServoLoop::~ServoLoop() = default;

namespace {

Eigen::Vector4d SwapPair(const Eigen::Vector4d& u) { return {u[2], u[3], u[0], u[1]}; }

}  // namespace

Eigen::Vector4d ServoLoop::Slot::U() const {
  const Eigen::Vector4d& u = state->extremum().u;
  return swapped ? SwapPair(u) : u;
}

Eigen::Vector3d ServoLoop::Slot::PointA() const {
  return swapped ? state->extremum().p_g : state->extremum().p_f;
}

Eigen::Vector3d ServoLoop::Slot::PointB() const {
  return swapped ? state->extremum().p_f : state->extremum().p_g;
}

void ServoLoop::Slot::Activate(const Eigen::Vector4d& u_pair) {
  state->Activate(swapped ? SwapPair(u_pair) : u_pair);
}

bool ServoLoop::Slot::Target(int a, int b) {
  if (!body_term || !body_term->Target(body_state, a, b)) return false;
  const int f = body_term->faces()[static_cast<size_t>(body_state->f)].id;
  const int g = body_term->faces()[static_cast<size_t>(body_state->g)].id;
  surface_a = std::min(f, g);
  surface_b = std::max(f, g);
  swapped = f > g;
  return true;
}

std::vector<contact::GlobalSurface> ServoLoop::GlobalSurfaces() const {
  std::vector<contact::GlobalSurface> out;
  for (const SceneSurface& s : scene_->surfaces) {
    out.push_back({s.body, &s.surface, s.watched ? &s.mesh : nullptr, s.trim ? &*s.trim : nullptr});
  }
  return out;
}

std::vector<std::pair<int, int>> ServoLoop::GlobalPairs() const {
  std::vector<std::pair<int, int>> out;
  for (const ContactPairSpec& p : scene_->pairs) out.emplace_back(p.surface_a, p.surface_b);
  return out;
}

std::vector<std::pair<int, int>> ServoLoop::GlobalBodyPairs() const {
  std::vector<std::pair<int, int>> out;
  for (const BodyPairSpec& p : scene_->body_pairs) out.emplace_back(p.body_a, p.body_b);
  return out;
}

Eigen::Vector3d ServoLoop::ToolPoint(const DeviceSample& d) const {
  const DeviceSpec& dv = scene_->device;
  const Eigen::Quaterniond Q(d.orientation[0], d.orientation[1], d.orientation[2],
                             d.orientation[3]);
  const Eigen::Vector3d p(d.position[0], d.position[1], d.position[2]);
  return device_origin_ + dv.scale * dv.R_WD * (p + Q * dv.tool_offset);
}

Eigen::Vector3d ServoLoop::GraspPoint() const {
  return poses_[static_cast<size_t>(grasp_at_.body)].Point(grasp_at_.point);
}

ServoLoop::TrackingCounts ServoLoop::Tracking() const {
  TrackingCounts c;
  for (const Slot& s : slots_) {
    c.tracked += s.state->tracked_steps;
    c.solves += s.state->solves;
    c.lost += s.state->lost;
  }
  return c;
}

int ServoLoop::active_contacts() const {
  int n = 0;
  for (const Slot& s : slots_) n += s.state->active;
  return n;
}

Eigen::Vector3d ServoLoop::GraspTarget() const { return target_; }

namespace {

// The follow step is bounded per tick by the speed times at most this much time, s: a servo that
// stalls lets the target lag rather than jump (the global stage and the solver's warm start
// both assume small steps; 2 ms at 1 m/s is 2 mm).
constexpr double kFollowStepTime = 2e-3;

}  // namespace

bool ServoLoop::Follow(const DeviceSample& d, double dt) {
  const DeviceSpec& dv = scene_->device;
  double n2 = 0.0;
  for (int i = 0; i < 3; ++i) {
    // The bridge's filter has already judged the sample: this is the second line of defence.
    if (!(d.position[i] >= dv.workspace_min[i] && d.position[i] <= dv.workspace_max[i])) {
      return false;
    }
  }
  for (int i = 0; i < 4; ++i) n2 += d.orientation[i] * d.orientation[i];
  if (!(std::abs(n2 - 1.0) < 1e-2)) return false;
  const Eigen::Vector3d p_WT = ToolPoint(d);  // the tool point in the world
  const double h = std::min(dt, kFollowStepTime);
  const Eigen::Vector3d step = p_WT - target_;
  const double max_step = dv.follow_speed * dv.scale * h;
  const double n = step.norm();
  target_ += n > max_step ? step * (max_step / n) : step;
  // The coupling saturates at max_force for the hand, so the scene is never pulled harder
  // either: the target stays within the saturation distance max_force / k of the grasp point
  // (a saturated virtual coupling; a hand 10 cm away drags the parts with 3.3 N, not 30 N).
  const Eigen::Vector3d p_WG = GraspPoint();
  const Eigen::Vector3d reach = target_ - p_WG;
  const double max_reach = dv.scale * dv.max_force / dv.stiffness;
  const double r = reach.norm();
  if (r > max_reach) target_ = p_WG + reach * (max_reach / r);
  if (grasp_orientation_) {
    const Eigen::Quaterniond Q_DT(d.orientation[0], d.orientation[1], d.orientation[2],
                                  d.orientation[3]);
    const Eigen::Quaterniond Q_WT = Eigen::Quaterniond(dv.R_WD) * Q_DT.normalized();
    const double angle = orientation_target_.angularDistance(Q_WT);
    const double max_angle = dv.follow_angular_speed * h;
    orientation_target_ =
        angle > max_angle ? orientation_target_.slerp(max_angle / angle, Q_WT) : Q_WT;
  }
  return target_.allFinite() && orientation_target_.coeffs().allFinite();
}

bool ServoLoop::Sane(const optimizer::SolveStats& st) const {
  if (!q_.allFinite() || !std::isfinite(st.max_violation) || !std::isfinite(st.kkt_residual)) {
    return false;
  }
  if (st.max_violation > options_.fault_violation) return false;
  if (!solver_->equality_multipliers().allFinite() ||
      !solver_->inequality_multipliers().allFinite()) {
    return false;
  }
  for (Eigen::Index b = 0; b + 7 <= q_.size(); b += 7) {
    if (q_.segment<3>(b).norm() > options_.fault_distance) return false;
  }
  return true;
}

void ServoLoop::KeepGood() {
  q_good_ = q_;  // (same sizes: Eigen assigns in place, no allocation)
  lambda_e_good_ = solver_->equality_multipliers();
  lambda_i_good_ = solver_->inequality_multipliers();
  for (Slot& s : slots_) {
    if (s.state->active) s.good_u = s.state->extremum().u;
    s.good_a = s.state->active ? s.surface_a : -1;
    s.good_b = s.state->active ? s.surface_b : -1;
  }
  target_good_ = target_;
  orientation_target_good_ = orientation_target_;
}

void ServoLoop::RestoreGood() {
  q_ = q_good_;
  solver_->set_multipliers(lambda_e_good_, lambda_i_good_);
  for (Slot& s : slots_) {
    if (!s.state->active) continue;
    if (s.body_term && (s.good_a != s.surface_a || s.good_b != s.surface_b)) {
      // A body slot moved to another face pair since: back to the good tick's, or free.
      if (s.good_a < 0 || !s.Target(s.good_a, s.good_b)) {
        s.state->Deactivate();
        continue;
      }
    }
    s.state->Reseed(s.good_u);
  }
  for (int k = 0; k < lines_.pairs(); ++k) {
    if (!lines_.line(k)) continue;
    const bool entered = lines_.entering(k);
    Eigen::Vector4d u;
    lines_.Leave(k, &u);
    if (!entered) ResumePoint(k, u);  // (else its point is still held)
  }
  target_ = target_good_;
  orientation_target_ = orientation_target_good_;
  grasp_state_->target = target_;
  if (grasp_orientation_state_)
    grasp_orientation_state_->R_target = orientation_target_.toRotationMatrix();
}

void ServoLoop::StartSession(int64_t session_index) {
  session_index_ = session_index;
  ramp_ = 0.0;
  f_D_.setZero();
  tau_D_.setZero();
  have_p_TG_D_ = false;
  last_seq_ = -1;
  last_answer_ns_ = 0;
  last_timeout_ns_ = 0;
  sent_f_D_.setZero();  // a new session's wrenches start from zero (its driver restarted)
  sent_ns_ = 0;
}

void ServoLoop::LimitAgainstSent(int64_t now_ns) {
  const DeviceSpec& dv = scene_->device;
  const double dt =
      sent_ns_ > 0 ? std::min(1e-9 * static_cast<double>(now_ns - sent_ns_), 2.0 / dv.device_rate)
                   : 0.0;
  const double max_step = dv.max_force_rate * std::max(dt, 0.0);
  const Eigen::Vector3d step = f_D_ - sent_f_D_;
  const double s = step.norm();
  if (s > max_step) f_D_ = sent_f_D_ + step * (max_step / s);
}

void ServoLoop::FillWrench(const DeviceSample& d, int64_t now_ns, int8_t state, WrenchSample* w) {
  sent_f_D_ = f_D_;
  sent_ns_ = now_ns;
  w->utime = d.utime;
  w->seq = d.seq;
  w->device_id = d.device_id;
  w->session = d.session;
  w->server_utime = now_ns / 1000;
  w->received_ns = d.received_ns;
  w->tick_start_ns = now_ns;
  for (int i = 0; i < 3; ++i) {
    w->force[i] = f_D_[i];
    w->torque[i] = options_.dof == 6 ? tau_D_[i] : 0.0;
  }
  w->state = state;
}

void ServoLoop::Tick(const DeviceSample* device, int64_t now_ns, TickResult* out) {
  const DeviceSpec& dv = scene_->device;
  // The server's own clock, for everything timed: the client's utime is only echoed.
  const double dt =
      last_tick_ns_ > 0 ? std::max(0.0, 1e-9 * static_cast<double>(now_ns - last_tick_ns_)) : 0.0;
  last_tick_ns_ = now_ns;
  ++ticks_;
  out->answered = out->fault = out->new_session = false;
  out->unanswered = 0;
  const InjectedFault inject = injected_;
  injected_ = InjectedFault{};
  DeviceSample injected_sample;
  if (device && inject.stage == InjectedFault::kDeviceState) {
    injected_sample = *device;
    injected_sample.position[0] = inject.value;
    device = &injected_sample;
  }
  if (device && device->session_index != session_index_) {
    StartSession(device->session_index);
    out->new_session = true;
  }
  const bool fresh =
      device && 1e-9 * static_cast<double>(now_ns - device->received_ns) <= options_.device_timeout;
  out->timed_out = device && !fresh;
  bool fault = MoveScene(fresh ? device : nullptr, dt, inject, out);

  // The ramp: up over ramp_time while the device is fresh, down while it is not (the force
  // scales down with it and the scene holds at the last target); a fault restarts it from zero.
  const double ramp_rate = dv.ramp_time > 0.0 ? dt / dv.ramp_time : 1.0;
  const double previous = ramp_;
  if (!fault) ramp_ = std::clamp(ramp_ + (fresh ? ramp_rate : -ramp_rate), 0.0, 1.0);
  if (!fresh) {
    RampDownSilent(device, now_ns, dt, previous, fault, out);
    return;
  }
  timeout_final_sent_ = false;
  if (device->seq == last_seq_) return;  // this sample is answered already
  if (device->accepted > last_accepted_ + 1) {
    out->unanswered = device->accepted - last_accepted_ - 1;
  }
  last_accepted_ = device->accepted;
  const double dt_answer =
      last_answer_ns_ > 0 ? 1e-9 * static_cast<double>(now_ns - last_answer_ns_) : 0.0;
  Eigen::Vector3d f_D = Eigen::Vector3d::Zero();
  Eigen::Vector3d tau_D = Eigen::Vector3d::Zero();
  if (!fault && !Couple(*device, dt_answer, inject, &f_D, &tau_D)) {
    fault = true;
    ramp_ = 0.0;
  }
  if (!RenderLimited(f_D, tau_D, now_ns)) fault = true;
  out->fault = fault;
  last_seq_ = device->seq;
  last_answer_ns_ = now_ns;
  last_answered_ = *device;
  out->answered = true;
  FillWrench(*device, now_ns, fault ? kFault : (ramp_ < 1.0 ? kRampingUp : kRunning), &out->wrench);
}

bool ServoLoop::MoveScene(const DeviceSample* fresh_device, double dt, const InjectedFault& inject,
                          TickResult* out) {
  // 1. The grasp targets follow the device; 2. the warm solve; 3. any non-finite or absurd
  // intermediate restores the last good state (configuration, multipliers, tracked contacts,
  // targets) and sends the force to zero.
  bool fault = fresh_device && !Follow(*fresh_device, dt);
  if (inject.stage == InjectedFault::kGoal) target_[0] = inject.value;
  KeepSplitRowsOffSaddles();
  optimizer::SolveStats st;
  const TrackingCounts before = Tracking();
  if (!fault && target_.allFinite() && target_.norm() <= options_.fault_distance) {
    grasp_state_->target = target_;
    if (grasp_orientation_state_)
      grasp_orientation_state_->R_target = orientation_target_.toRotationMatrix();
    // The bound's time is the follow's (at most kFollowStepTime); the first tick, which has no
    // time step yet, gets that much too rather than no bound. The parts it bounds are marked
    // when the solve first steps (BoundSnappingParts, the solver's motion marker).
    const double h = dt > 0.0 ? std::min(dt, kFollowStepTime) : kFollowStepTime;
    solver_->set_max_solve_motion(std::max(0.0, options_.max_part_speed) * h);
    st = solver_->Solve(&q_);
    bound_lagging_ = st.motion_bounded_steps > 0;
    if (inject.stage == InjectedFault::kSolverResult) q_[0] = inject.value;
    fault = !Sane(st);
  } else {
    fault = true;
  }
  if (fault) {
    RestoreGood();
    ramp_ = 0.0;
    out->violation = good_violation_;
  } else {
    KeepGood();
    good_violation_ = st.max_violation;
    out->violation = st.max_violation;
  }
  problem_->mechanism().Poses(q_, &poses_);
  if (!fault) {
    FollowLines();
    if (faces_.pairs() > 0) faces_.Follow();
  }
  out->fault = fault;
  out->iterations = st.iterations;
  out->bounded = st.motion_marked;
  out->stopped_at_bound = st.stopped_at_bound;
  out->kkt = st.kkt_residual;
  out->num_contacts = active_contacts();
  const TrackingCounts after = Tracking();
  out->tracked = after.tracked - before.tracked;
  out->solves = after.solves - before.solves;
  out->lost = after.lost - before.lost;
  return fault;
}

void ServoLoop::RampDownSilent(const DeviceSample* device, int64_t now_ns, double dt,
                               double previous_ramp, bool fault, TickResult* out) {
  // Silent device: the force follows the ramp down, never faster than the rate limit; one
  // timeout wrench per device period until it is zero (a driver still listening renders the
  // ramp instead of holding its last force).
  const DeviceSpec& dv = scene_->device;
  const double scale = previous_ramp > 0.0 ? ramp_ / previous_ramp : 0.0;
  const Eigen::Vector3d goal = f_D_ * scale;
  const double max_step = dv.max_force_rate * dt;
  const Eigen::Vector3d step = goal - f_D_;
  f_D_ += step.norm() > max_step ? Eigen::Vector3d(step * (max_step / step.norm())) : step;
  tau_D_ *= scale;
  have_p_TG_D_ = false;
  const bool due = 1e-9 * static_cast<double>(now_ns - last_timeout_ns_) >= 1.0 / dv.device_rate;
  if (device && last_seq_ >= 0 && due && !timeout_final_sent_) {
    LimitAgainstSent(now_ns);  // a late tick's ramp step is held to two periods' worth
    FillWrench(last_answered_, now_ns, fault ? kFault : kTimeout, &out->wrench);
    out->answered = true;
    last_timeout_ns_ = now_ns;
    timeout_final_sent_ = f_D_.isZero(0.0) && tau_D_.isZero(0.0);
  }
}

bool ServoLoop::Couple(const DeviceSample& device, double dt_answer, const InjectedFault& inject,
                       Eigen::Vector3d* f_D, Eigen::Vector3d* tau_D) {
  // Virtual coupling at the hand (device frame): the grasp point's offset from the tool point
  // (the device's own, not the following target: after a jump the force, not a teleport, tells
  // the hand where the part is), mapped back through the workspace scale, with damping on its
  // rate of change over the server's time between answers: p_TG_D is the grasp point G's offset
  // from the tool point T in the device frame D (device metres), f_D and tau_D the wrench on the
  // hand in D.
  const DeviceSpec& dv = scene_->device;
  const Eigen::Vector3d p_TG_D =
      dv.R_WD.transpose() * (GraspPoint() - ToolPoint(device)) / dv.scale;
  Eigen::Vector3d v_TG_D = Eigen::Vector3d::Zero();
  if (have_p_TG_D_ && dt_answer > 0.0) v_TG_D = (p_TG_D - p_TG_D_prev_) / std::max(dt_answer, 1e-4);
  *f_D = dv.stiffness * p_TG_D + dv.damping * v_TG_D;
  if (inject.stage == InjectedFault::kCoupling) (*f_D)[0] = inject.value;
  if (grasp_orientation_) {
    // τ on the hand = R ¼ G(Q) ∂E/∂Q (the reaction of the body-frame torque −¼ G(Q) ∂E/∂Q
    // that the orientation coupling exerts on the grasped body; seed 001 Eq. 5), device frame.
    grasp_orientation_->Evaluate(poses_, grasp_orientation_state_, r9_, J9_, J9b_);
    const contact::BodyPose& X_WB = poses_[static_cast<size_t>(grasp_at_.body)];
    const Eigen::Vector4d dE_dQ =
        0.5 * scene_->grasp.rotational_stiffness * J9_.rightCols<4>().transpose() * r9_;
    *tau_D = dv.R_WD.transpose() * X_WB.R_WB *
             contact::TorqueFromQuaternionForce(X_WB.q.tail<4>(), dE_dQ);
  }
  // A force beyond fault_force_factor × max_force (or one whose square overflows) is absurd:
  // a fault like a non-finite one.
  const double absurd = options_.fault_force_factor * dv.max_force;
  if (!(f_D->squaredNorm() <= absurd * absurd) || !std::isfinite(tau_D->squaredNorm())) {
    f_D->setZero();
    tau_D->setZero();
    return false;
  }
  p_TG_D_prev_ = p_TG_D;
  have_p_TG_D_ = true;
  return true;
}

bool ServoLoop::RenderLimited(Eigen::Vector3d f_D, Eigen::Vector3d tau_D, int64_t now_ns) {
  const DeviceSpec& dv = scene_->device;
  const double f = f_D.norm();
  if (f > dv.max_force) f_D *= dv.max_force / f;
  f_D *= ramp_;
  tau_D *= ramp_;
  // Force-rate limit against the last wrench sent (an answer or a timeout wrench), on the
  // server's clock, and at most two device periods' worth per wrench (a device holds its last
  // force between wrenches: a late answer must not step further than a punctual one could).
  f_D_ = f_D;
  LimitAgainstSent(now_ns);
  if (f_D_.norm() > dv.max_force) f_D_ *= dv.max_force / f_D_.norm();
  tau_D_ = tau_D;
  if (!f_D_.allFinite() || !tau_D_.allFinite()) {  // unreachable: the last line of defence
    f_D_.setZero();
    tau_D_.setZero();
    return false;
  }
  return true;
}

void ServoLoop::FillSnapshot(Snapshot* s) const {
  s->tick = ticks_;
  s->num_bodies = static_cast<int32_t>(poses_.size());
  for (size_t b = 0; b < poses_.size(); ++b) {
    for (int i = 0; i < 7; ++i) s->q[b][i] = poses_[b].q[i];
  }
  int n = 0;
  const Eigen::VectorXd& lambda = solver_->inequality_multipliers();
  for (const Slot& slot : slots_) {
    if (!slot.state->active || n >= kMaxContacts) continue;
    TrackedContact& c = s->contacts[n++];
    c.surface_a = slot.surface_a;
    c.surface_b = slot.surface_b;
    c.body_a = scene_->surfaces[static_cast<size_t>(c.surface_a)].body;
    c.body_b = scene_->surfaces[static_cast<size_t>(c.surface_b)].body;
    const Eigen::Vector4d u = slot.U();
    const Eigen::Vector3d p_a = slot.PointA(), p_b = slot.PointB();
    for (int i = 0; i < 4; ++i) c.u[i] = u[i];
    c.beta = slot.state->extremum().beta;
    c.form = static_cast<int32_t>(slot.state->form);
    for (int i = 0; i < 3; ++i) {
      c.p_a[i] = p_a[i];
      c.p_b[i] = p_b[i];
    }
    c.force = slot.row >= 0 && slot.row < lambda.size()
                  ? scene_->device.stiffness * lambda[slot.row]
                  : 0.0;
  }
  FillLineContacts(s, &n);
  FillFaceContacts(s, &n);
  s->num_contacts = n;
  const Eigen::Vector3d t = grasp_state_->target;
  for (int i = 0; i < 3; ++i) s->grasp_target[i] = t[i];
}

}  // namespace tangent::server
