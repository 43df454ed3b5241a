#pragma once

// The servo loop's work for one tick (design.md §2), free of threads and I/O: map the device
// pose into the scene, apply contact events, solve warm, compute the wrench of the virtual
// coupling. Daemon (daemon.h) runs it on its own core; tests and benchmarks call it directly.

#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "contact/global.h"
#include "optimizer/body_contacts.h"
#include "optimizer/clearance_guard.h"
#include "optimizer/contacts.h"
#include "optimizer/goals.h"
#include "optimizer/problem.h"
#include "optimizer/solver.h"
#include "server/face_contacts.h"
#include "server/line_contacts.h"
#include "server/messages.h"
#include "server/scene.h"

namespace tangent::server {

struct ServoOptions {
  int dof = 3;              ///< 3: force only; 6: force and torque
  int max_iterations = 10;  ///< solver iterations per tick
  /// Stationarity tolerance of a tick's solve, |∇E − Jᵀλ|∞ in the units where the grasp has
  /// weight 1 (metres): times the coupling stiffness it is a force balance error, 1e-8 m x
  /// 300 N/m = 3 µN. Constraints and complementarity stay at 1e-10. (Measured with
  /// bench/servo_profile on the paperclip drag: 1e-6, 1e-7 and 1e-8 give the same iteration
  /// counts, Newton's last step lands far below all three.)
  double kkt_tolerance = 1e-8;
  double device_timeout = 0.1;  ///< s without device states: force ramps to zero, scene holds
  /// A tick whose solve leaves a constraint violation above this is a fault (the scene is
  /// restored): 1 cm is 1e8 times the servo's constraint tolerance and far above any transient
  /// measured on the drag (worst 1e-10 m, docs/server.md), so only a broken solve reaches it.
  double fault_violation = 1e-2;
  /// A body farther than this from the world origin is a fault, m: a desk device's workspace
  /// times any sensible scale is metres; beyond this a part has been thrown away.
  double fault_distance = 100.0;
  /// A coupling force above this many times the device's saturation is a fault: the workspace
  /// bounds the coupling's spring term (k · 0.2 m ≈ 60 N at 300 N/m) and a 10 cm jump's damping
  /// term is ≈ 100 N, so only a broken state reaches a thousand times 3.3 N.
  double fault_force_factor = 1e3;
  /// How contact slots follow their pairs between solves (defaults exact; bench/speed_error
  /// sweeps the alternatives, docs/benchmarks.md).
  optimizer::ContactTracking tracking;
  /// Line contacts (server/line_contacts.h): a nearly conformal contact of a declared pair of
  /// untrimmed surfaces is held by three sections across its line instead of its one point,
  /// spaced so that the gap dips at most LineContactOptions::dip between them. With the floor
  /// below, the paperclip soak holds the chain for the hour (docs/reliability.md, "Soak").
  bool line_contacts = true;
  LineContactOptions line;
  /// Face contacts (server/face_contacts.h): a declared pair of two untrimmed flat faces is held
  /// by the corners of each lying over the other (contact::GlobalOptions::face_pairs). Off, such
  /// a pair has slots as any other, and nothing finds it (docs/contact.md, "Face contacts").
  bool face_contacts = true;
  /// optimizer::SolverOptions::step_reach (off by default, as line_contacts).
  bool step_reach = false;
  /// optimizer::SolverOptions::bounded_normal_step (off by default).
  bool bounded_normal_step = false;
  /// optimizer::SolverOptions::indefinite_floor: 10 (the solver's own default is 0). Without it
  /// a line-held clip's nearly free turn takes steps of millimetres along an eigenvalue near
  /// zero, and the soak comes apart in five of six runs (docs/reliability.md, "Soak").
  double indefinite_floor = 10.0;
  /// No tunnelling (docs/stability.md): every step is kept within the global stage's last
  /// clearance certificate (AdoptClearances), so no pair of parts certified apart can pass
  /// through each other before the stage looks again, however late that is.
  bool clearance_guard = true;
  /// m/s: a part one of whose contacts is near a pitchfork of its distance (λ_min of the
  /// relative curvature below a tenth of λ_max at the tick's start: a clip turning towards
  /// parallel in another's hook, free to turn) moves no point faster than this, times the
  /// tick's own time step (at most 2 ms, as the follow's; 2 ms on the first tick), in that
  /// tick's solve (optimizer::SolverOptions::max_solve_motion; 0: no bound). Without it one
  /// solve moved such a clip 3.4 mm, through the other's wire (docs/reliability.md, "Soak").
  /// 0.2 m/s is 40 times the demo's drag.
  double max_part_speed = 0.2;
};

/// Test hooks: a one-shot value injected into one stage of the next tick, to show that a
/// non-finite or absurd intermediate there is caught (ServoTest.*Fault*).
struct InjectedFault {
  enum Stage { kNone, kDeviceState, kGoal, kSolverResult, kCoupling } stage = kNone;
  double value = 0.0;
};

struct TickResult {
  WrenchSample wrench;
  bool answered = false;  ///< a new device sample was consumed (wrench answers it)
  int iterations = 0;
  double violation = 0.0;
  double kkt = 0.0;  ///< stationarity residual of the tick's solve
  int num_contacts = 0;
  bool timed_out = false;
  bool fault = false;      ///< a non-finite or absurd intermediate: scene restored, force to zero
  int64_t unanswered = 0;  ///< accepted states skipped before the one this tick answered
  bool new_session = false;
  /// Contact tracking in this tick's solve: evaluations the tracker answered, evaluations that
  /// needed a full extremal solve, and tracker steps that reported `lost` (each then re-solved
  /// from the last parameters: a defined event, counted, never a silent jump).
  int64_t tracked = 0, solves = 0, lost = 0;
  /// This tick's solve stepped with parts near a pitchfork of a contact's distance marked for
  /// the motion bound (ServoOptions::max_part_speed).
  bool bounded = false;
  /// This tick's solve stopped at its motion bound, unconverged (SolveStats::stopped_at_bound).
  bool stopped_at_bound = false;
};

class ServoLoop {
 public:
  /// Builds the problem: joints, floating contacts (found at the initial poses: @throws
  /// SceneError when one is not touching), contact slots for unilateral pairs, the grasp
  /// (position goal; orientation goal for 6-DOF), objectives. Runs one global pass at the initial
  /// poses to activate the contacts present there.
  /// The scene must outlive the loop; the loop never changes it.
  ServoLoop(const Scene& scene, const ServoOptions& options);
  ~ServoLoop();

  /// One tick (allocation free). `device`: the latest accepted sample (nullptr: none yet);
  /// `now_ns`: CLOCK_MONOTONIC.
  void Tick(const DeviceSample* device, int64_t now_ns, TickResult* out);
  /// Applies a global-stage event: activates a free slot of the pair / frees the active slot
  /// tracking the event's parameters (within 5 % of each parameter's domain). A face pair
  /// covered by a declared body pair takes a free slot of the body pair's pool, moved to that
  /// face pair. @return false when no slot was free, or no active slot tracks the removed
  /// contact (counted by the caller).
  bool Apply(const ContactEventMsg& e);
  void FillSnapshot(Snapshot* s) const;
  /// Takes the global stage's clearance certificate (GlobalLink::clearances()) for the next
  /// ticks' steps (allocation free): refused when it is not this scene's, when the guard is off,
  /// or while the configuration has moved beyond it since its snapshot (the guard then keeps
  /// the certificate it has, which holds the configuration). @return whether it was taken.
  bool AdoptClearances(const ClearanceMsg& m);
  const optimizer::ClearanceGuard& clearance_guard() const { return guard_; }

  /// The global stage's view of the scene (surfaces in scene order; declared surface pairs;
  /// declared body pairs).
  std::vector<contact::GlobalSurface> GlobalSurfaces() const;
  std::vector<std::pair<int, int>> GlobalPairs() const;
  std::vector<std::pair<int, int>> GlobalBodyPairs() const;

  const Eigen::VectorXd& q() const { return q_; }
  const Scene& scene() const { return *scene_; }
  /// The global stage's settings for this servo: the scene's, taking continua of minima as
  /// contacts when line contacts are on (contact::GlobalOptions::accept_continuum).
  contact::GlobalOptions GlobalStageOptions() const {
    contact::GlobalOptions o = scene_->global;
    o.accept_continuum = options_.line_contacts;
    o.continuum_ratio = options_.line.enter;
    o.face_pairs = options_.face_contacts;
    return o;
  }
  /// p_WT: a device sample's tool point T in the world W (m).
  Eigen::Vector3d ToolPoint(const DeviceSample& d) const;
  /// p_WG: the grasp point G on the grasped body in the world W (m).
  Eigen::Vector3d GraspPoint() const;
  int active_contacts() const;
  /// The line contacts' sections (server/line_contacts.h).
  const LineContacts& lines() const { return lines_; }
  /// Line pair k's section loads (middle, then either side), N: their multipliers in the units
  /// of the reported contact forces.
  Eigen::Vector3d LineLoads(int k) const {
    Eigen::Vector3d f;
    for (int i = 0; i < LineContacts::kSections; ++i) {
      f[i] = scene_->device.stiffness * solver_->inequality_multipliers()[lines_.row(k, i)];
    }
    return f;
  }
  /// The face contacts' corner rows (server/face_contacts.h).
  const FaceContacts& faces() const { return faces_; }
  /// Face pair k's corner loads (N; FaceContacts' order): their multipliers in the units of the
  /// reported contact forces.
  double FaceLoad(int k, int i) const {
    return scene_->device.stiffness * solver_->inequality_multipliers()[faces_.row(k, i)];
  }
  const optimizer::Problem& problem() const { return *problem_; }
  /// The grasp goal's target (world, m): follows the tool point at the device's follow speed.
  Eigen::Vector3d GraspTarget() const;
  /// Contact tracking totals over the contact slots since the start (TickResult's, summed).
  struct TrackingCounts {
    int64_t tracked = 0, solves = 0, lost = 0;
  };
  TrackingCounts Tracking() const;
  /// Injects a fault into the next tick (tests).
  void InjectFault(const InjectedFault& f) { injected_ = f; }

 private:
  struct Slot {
    /// The pair's surfaces, a < b: fixed for a declared face pair; for a body pair's slot the
    /// face pair it was last moved to (−1 before).
    int surface_a = 0, surface_b = 0;
    int row = 0;  ///< inequality row (multiplier index)
    bool floating = false;
    /// The term's f is surface_b and its g surface_a (a trimmed contact measures the trimmed
    /// surface as its f): its parameters are (s, t, u, v) in the pair's order.
    bool swapped = false;
    /// A SurfaceContactTerm, or a TrimmedContactTerm on a trimmed pair, or a BodyContactTerm
    /// in a body pair's pool.
    optimizer::TermPtr term;
    optimizer::ContactSlotState* state = nullptr;      ///< its data in solver_
    Eigen::Vector4d good_u = Eigen::Vector4d::Zero();  ///< tracked parameters, last good tick
    /// A body pair's slot: its pool (index into Scene::body_pairs), its term and the term's data.
    int body_pair = -1;
    const optimizer::BodyContactTerm* body_term = nullptr;
    optimizer::BodyContactTerm::State* body_state = nullptr;
    int good_a = -1, good_b = -1;  ///< the body slot's face pair at the last good tick (−1 free)
    int line = -1;  ///< its pair's index in lines_ (a declared untrimmed unilateral pair), or −1
    bool plain = false;  ///< its term is a SurfaceContactTerm (a declared untrimmed pair)
    /// Moves a body pair's slot to surfaces (a, b) (allocation free); false if not its faces.
    bool Target(int a, int b);
    /// The contact in the pair's order (a's parameters first; p_a on a).
    Eigen::Vector4d U() const;
    Eigen::Vector3d PointA() const;
    Eigen::Vector3d PointB() const;
    void Activate(const Eigen::Vector4d& u_pair);
  };

  /// Moves the grasp targets toward the device's tool pose, at most the follow speeds times dt.
  /// @return false when the sample is not sane (not finite, outside the workspace).
  bool Follow(const DeviceSample& d, double dt);
  /// Whether the solve left a finite, sane configuration.
  bool Sane(const optimizer::SolveStats& st) const;
  /// Keeps / restores the last good configuration, multipliers and tracked contacts.
  void KeepGood();
  void RestoreGood();
  /// Starts a new device session's coupling: zero force, a new ramp.
  void StartSession(int64_t session_index);
  /// The tick's steps. MoveScene: the targets follow a fresh device (nullptr: hold), the warm
  /// solve, and the last good state restored on a fault (returned true).
  bool MoveScene(const DeviceSample* fresh_device, double dt, const InjectedFault& inject,
                 TickResult* out);
  /// A silent device: the rendered wrench follows the ramp down within the rate limit; timeout
  /// wrenches once per device period until it is zero.
  void RampDownSilent(const DeviceSample* device, int64_t now_ns, double dt, double previous_ramp,
                      bool fault, TickResult* out);
  /// The virtual coupling's wrench on the hand in the device frame; false (and zero) when it is
  /// absurd or not finite.
  bool Couple(const DeviceSample& device, double dt_answer, const InjectedFault& inject,
              Eigen::Vector3d* f_D, Eigen::Vector3d* tau_D);
  /// Saturates, ramps and rate-limits the wrench into f_D_, tau_D_; false if they were not
  /// finite (zeroed).
  bool RenderLimited(Eigen::Vector3d f_D, Eigen::Vector3d tau_D, int64_t now_ns);
  /// The force-rate limit (docs/server.md): f_D_ moved to within max_force_rate × (server time
  /// since the last wrench sent, capped at two device periods) of that wrench's force. Every
  /// wrench sent passes it (answers and timeout wrenches alike): the device holds the last
  /// force it got, so the step it renders is the step between consecutive wrenches.
  void LimitAgainstSent(int64_t now_ns);
  /// Fills the wrench answering `d` (or the timeout wrench) from f_D_ and tau_D_, and records it
  /// as the last sent.
  void FillWrench(const DeviceSample& d, int64_t now_ns, int8_t state, WrenchSample* w);

  const Scene* scene_;
  Eigen::Vector3d device_origin_;  ///< world, m: the scene's, or the grasp point at rest
  ServoOptions options_;
  std::unique_ptr<optimizer::Problem> problem_;
  std::unique_ptr<optimizer::Solver> solver_;
  std::shared_ptr<optimizer::PositionGoalTerm> grasp_;
  std::shared_ptr<optimizer::OrientationGoalTerm> grasp_orientation_;
  // The grasp goals' data in solver_ (their targets).
  optimizer::PositionGoalTerm::State* grasp_state_ = nullptr;
  optimizer::OrientationGoalTerm::State* grasp_orientation_state_ = nullptr;
  optimizer::Attachment grasp_at_;
  std::vector<Slot> slots_;
  LineContacts lines_;
  /// The step's clearance guard (servo_clearance.cc), armed from the constructor's pass.
  optimizer::ClearanceGuard guard_;
  /// Configures the guard and takes its first certificate from the constructor's cold pass
  /// (`stage`, run at `pass_poses`).
  void StartClearanceGuard(const contact::GlobalContactStage& stage,
                           const std::vector<contact::BodyPose>& pass_poses);
  /// After a good tick: line-like contacts go to line mode (their rows retired, the sections
  /// placed), lines follow, and lines no longer line-like resume their point contact (lines_).
  void FollowLines();
  /// Marks for the tick motion bound the bodies of contacts near a pitchfork of their distance
  /// (ServoOptions::max_part_speed), and keeps those of the last tick marked while its bound
  /// held them back (bound_lagging_); false when none is.
  bool BoundSnappingParts();
  /// Before each solve: rows whose pair has another row (the minima of a split) keep to their
  /// own minimum (SurfaceContactTerm::State::keep_off_saddles), lone rows do not. Allocation
  /// free; nothing while no pair has two rows and no row changed.
  void KeepSplitRowsOffSaddles();
  /// λ_min / λ_max below which a contact is near a pitchfork (BoundSnappingParts): the line
  /// contacts' entry ratio (LineContactOptions::enter).
  static constexpr double kSnapCurvature = 0.1;
  /// Activates a free slot of line pair `line` at u (pair order), if one is free.
  void ResumePoint(int line, const Eigen::Vector4d& u);
  /// The snapshot's contacts from *count on: each pair in line mode as its middle section.
  void FillLineContacts(Snapshot* s, int* count) const;
  // (FollowLines, ResumePoint and FillLineContacts are in servo_lines.cc.)
  FaceContacts faces_;
  /// The snapshot's contacts from *count on: each held face pair as its lowest corner, with the
  /// corners' load (servo_faces.cc).
  void FillFaceContacts(Snapshot* s, int* count) const;
  Eigen::VectorXd q_;
  std::vector<contact::BodyPose> poses_;
  // Last good state (restored after a fault).
  Eigen::VectorXd q_good_, lambda_e_good_, lambda_i_good_;
  Eigen::Vector3d target_good_ = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation_target_good_ = Eigen::Quaterniond::Identity();
  // Grasp targets (world): they follow the tool pose at bounded speed.
  Eigen::Vector3d target_ = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation_target_ = Eigen::Quaterniond::Identity();
  InjectedFault injected_;
  // Coupling state (server clock only: the client's utime is echoed, never used).
  int64_t session_index_ = 0;
  int64_t last_seq_ = -1;
  int64_t last_accepted_ = 0;        ///< accepted index of the last sample answered
  int64_t last_answer_ns_ = 0;       ///< server time of the last answer
  int64_t last_timeout_ns_ = 0;      ///< server time of the last timeout wrench
  DeviceSample last_answered_;       ///< echoed by timeout wrenches
  bool timeout_final_sent_ = false;  ///< the zero-force timeout wrench has gone
  /// The last tick's motion bound shortened a step: its parts lag where the solve would take
  /// them, and stay bounded until they have caught up (else the first tick without the bound
  /// moves them the whole lag at once: 1.65 mm through the other wire, SnapTest).
  bool bound_lagging_ = false;
  /// KeepSplitRowsOffSaddles' bookkeeping: the plain rows changed since it last looked (an
  /// event, a line pair's point retired or resumed), and whether some pair has two rows. While
  /// neither holds it costs nothing.
  bool rows_changed_ = true;
  bool split_rows_ = false;
  double good_violation_ = 0.0;  ///< violation of the last good tick
  // The coupling (T the tool point, G the grasp point, D the device frame; device units): the
  // last p_TG_D, and the wrench on the hand after the rate limit, f_D_ (N) and tau_D_ (N·m).
  Eigen::Vector3d p_TG_D_prev_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d f_D_ = Eigen::Vector3d::Zero(), tau_D_ = Eigen::Vector3d::Zero();
  /// The force of the last wrench sent in this session and its server time (0: none yet).
  Eigen::Vector3d sent_f_D_ = Eigen::Vector3d::Zero();
  int64_t sent_ns_ = 0;
  double ramp_ = 0.0;  ///< 0..1
  int64_t last_tick_ns_ = 0;
  int64_t ticks_ = 0;
  bool have_p_TG_D_ = false;
  Eigen::Matrix<double, 9, 1> r9_;
  Eigen::Matrix<double, 9, 7> J9_, J9b_;
};

}  // namespace tangent::server
