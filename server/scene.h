#pragma once

// Scene files (JSON): bodies made of NURBS surfaces, joints, the surface pairs that may touch,
// the grasp, objectives and the device mapping. docs/server.md "Scene files" is the reference.

#include <deque>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "contact/global.h"
#include "nurbs/offset.h"
#include "nurbs/surface.h"
#include "nurbs/trim.h"
#include "optimizer/joints.h"
#include "optimizer/mechanism.h"
#include "optimizer/term.h"
#include "server/device_filter.h"

namespace tangent::server {

/// A scene file error: the message names the file and the offending item
/// ("scenes/x.json: bodies[1].mass: must be positive, got -2").
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct SceneSurface {
  std::string name;
  int body = 0;
  nurbs::NurbsSurface surface;  ///< in the body's frame, metres
  nurbs::OffsetMesh mesh;       ///< offset mesh for the global stage (built for declared pairs)
  bool watched = false;         ///< in a declared contact pair
  /// The material that remains (docs/trimming.md): the surface entry's "trim", or its NURBS
  /// document's. Validated at load; contacts on it measure only the material, and its offset
  /// mesh is cut along it.
  std::optional<nurbs::TrimmedDomain> trim;
};

struct ContactPairSpec {
  int surface_a = 0, surface_b = 0;
  /// Non-penetration (β ≥ 0, contacts found and retired by the global stage), or a floating
  /// contact (β = 0, must touch at the initial poses and always kept).
  enum class Kind { kUnilateral, kFloating } kind = Kind::kUnilateral;
  int max_contacts = 2;  ///< contact slots reserved for this pair (unilateral)
};

/// Contact declared between two bodies ("these two parts may touch", docs/cad.md): every face of
/// one against every face of the other, found by the global stage, kept in a pool of slots that
/// move between face pairs (optimizer/body_contacts.h). Non-penetration only.
struct BodyPairSpec {
  int body_a = 0, body_b = 0;
  int max_contacts = 4;  ///< contact slots reserved for the pair, shared by all its face pairs
};

struct JointSpec {
  std::string name;  ///< the scene's "name", or "joint <index>"
  std::string type;  ///< spherical, revolute, universal, cylindrical, prismatic, fixed
  optimizer::Attachment a, b;
  optimizer::TermPtr term;
  optimizer::TermPtr limits;              ///< revolute limits (may be null)
  double limit_lo = 0.0, limit_hi = 0.0;  ///< the limits' range, rad (when limits is set)
};

struct ObjectiveSpec {
  optimizer::TermPtr term;
  double weight = 1.0;
};

struct GraspSpec {
  int body = -1;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< grasp point, body frame, metres
  /// Weight of the grasped body's orientation toward its initial orientation (3-DOF devices:
  /// keeps the grasped part from spinning about the grasp point), relative to the grasp.
  double hold_orientation = 0.0;
  /// 6-DOF devices: rotational coupling stiffness, N·m/rad.
  double rotational_stiffness = 0.02;
};

/// Device workspace → scene: p_W = origin + scale · R (p_device + R_stylus tool_offset).
struct DeviceSpec {
  double scale = 1.0;
  /// World point of the device origin, m; when the scene gives none, the grasp point at rest
  /// (the stylus starts where the part is held).
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  bool origin_given = false;
  /// The device frame D's orientation in the world W (the scene's device.quaternion).
  Eigen::Matrix3d R_WD = Eigen::Matrix3d::Identity();
  Eigen::Vector3d tool_offset = Eigen::Vector3d::Zero();  ///< stylus frame, device metres
  double stiffness = 300.0;                               ///< virtual coupling, N/m at the hand
  double damping = 1.0;                                   ///< N·s/m at the hand
  double max_force = 3.3;                                 ///< N (a Touch-class device's saturation)
  double rated_stiffness = 500.0;                         ///< the device's own limit, N/m
  /// The device served (device_state_t.device_id): the scene's "id", or tangentd --device-id.
  /// With neither, tangentd serves no device (docs/server.md "Device sessions").
  std::optional<int64_t> id;
  double device_rate = 1000.0;    ///< Hz, the rate the device renders our force at
  double max_force_rate = 500.0;  ///< N/s
  double ramp_time = 1.0;         ///< s, force ramp at start-up and after a timeout
  /// The device's workspace box, device frame, m: states outside are rejected (DeviceFilter).
  /// Default: kTouchWorkspace.
  Eigen::Vector3d workspace_max =
      Eigen::Vector3d(kTouchWorkspace[0], kTouchWorkspace[1], kTouchWorkspace[2]);
  Eigen::Vector3d workspace_min = -workspace_max;
  /// Speed at which the grasp target follows the stylus, m/s in the device frame (× scale in
  /// the scene): a hand's fast moves (≤ 1 m/s) are followed at once, a jump becomes a
  /// continuous path, and meanwhile the coupling force tells the hand where the part is.
  double follow_speed = 1.0;
  double follow_angular_speed = 10.0;  ///< rad/s, the same for the 6-DOF orientation target
};

struct Scene {
  std::string name;
  std::string path;
  optimizer::Mechanism mechanism;
  std::deque<SceneSurface> surfaces;  ///< stable addresses
  std::vector<JointSpec> joints;
  std::vector<ContactPairSpec> pairs;
  std::vector<BodyPairSpec> body_pairs;
  std::vector<ObjectiveSpec> objectives;
  GraspSpec grasp;
  DeviceSpec device;
  /// Weight of least astonishment (the kinetic-energy metric's step penalty) relative to the
  /// grasp, whose weight is 1 (docs/server.md, "Least astonishment").
  double least_astonishment = 1e-3;
  double offset_tolerance = 20e-6;  ///< tessellation bound of offset meshes, m
  double offset_margin = 0.25e-3;   ///< m
  /// Longest grid-cell chord of the offset meshes, m: small blocks let the global stage skip the
  /// overlap around tracked contacts (docs/contact.md); keep it well below 4 x 1 mm.
  double offset_max_edge = 0.5e-3;
  /// The global contact stage's settings ("global_stage": activation, release, max_penetration,
  /// neglect_radius, in the scene's length unit; contact/global.h). The spheres of neglect must
  /// cover where a tracked contact's offsets overlap, about √(4 r R) across for offset r and
  /// relative curvature radius R: parts of centimetres need more than the paperclips' 1 mm.
  contact::GlobalOptions global;
  std::vector<std::string> load_log;  ///< certification lines etc.

  /// Index of a body, surface or joint by name, -1 if none.
  int BodyIndex(const std::string& name) const;
  int SurfaceIndex(const std::string& name) const;
  int JointIndex(const std::string& name) const;
};

struct SceneLoadOptions {
  /// Build and certify the offset meshes of watched surfaces (the global stage needs them).
  /// Off only where a scene is read for its description alone: the scene fuzzer, which would
  /// otherwise spend its time certifying the example scenes' meshes (tested on their own).
  bool offset_meshes = true;
};

/// Parses a scene. `where` names the source in error messages. @throws SceneError.
std::unique_ptr<Scene> ParseScene(const std::string& text, const std::string& where,
                                  const std::string& base_dir = ".",
                                  const SceneLoadOptions& options = {});
/// Loads a scene file (NURBS files it names are resolved relative to it). @throws SceneError.
std::unique_ptr<Scene> LoadScene(const std::string& path);

}  // namespace tangent::server
