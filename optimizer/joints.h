#pragma once

#include "optimizer/term.h"

namespace tangent::optimizer {

/// Where a joint or goal attaches to a body: a point (body frame, m) and, for axis joints, a
/// unit axis and a unit reference direction perpendicular to it (body frame).
struct Attachment {
  int body = -1;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d reference = Eigen::Vector3d::UnitX();
};

/// Joint constraints (equalities r = 0). Each is a Term on the two attached bodies.
/// Spherical: the attachment points coincide (3 rows).
TermPtr SphericalJoint(const Attachment& a, const Attachment& b);
/// Revolute: points coincide, axes parallel (5 rows: 3 + 2, the axis of a against two directions
/// perpendicular to b's axis).
TermPtr RevoluteJoint(const Attachment& a, const Attachment& b);
/// Universal: points coincide, a's axis perpendicular to b's axis (3 + 1 rows).
TermPtr UniversalJoint(const Attachment& a, const Attachment& b);
/// Cylindrical: axes parallel and b's point on a's axis line (2 + 2 rows).
TermPtr CylindricalJoint(const Attachment& a, const Attachment& b);
/// Prismatic: cylindrical plus no rotation about the axis, a's reference parallel to b's
/// (4 + 1 rows).
TermPtr PrismaticJoint(const Attachment& a, const Attachment& b);
/// Fixed (weld): points coincide, axes parallel, references parallel (3 + 2 + 1 rows).
TermPtr FixedJoint(const Attachment& a, const Attachment& b);
/// The joint of a type named as in scene files: spherical, revolute, universal, cylindrical,
/// prismatic or fixed. @throws std::invalid_argument for another name.
TermPtr MakeJoint(const std::string& type, const Attachment& a, const Attachment& b);
/// |Q|² − 1 = 0 for a moving body (1 row).
TermPtr UnitQuaternion(int body);
/// Revolute joint limits as two inequalities θ − lo ≥ 0 and hi − θ ≥ 0, θ the angle of b's
/// reference about a's axis from a's reference (right-handed), in (−π, π].
TermPtr RevoluteLimits(const Attachment& a, const Attachment& b, double lo, double hi);
/// The joint angle θ of RevoluteLimits (for tests and reports).
double RevoluteAngle(const Attachment& a, const Attachment& b, const std::vector<BodyPose>& poses);
/// Prismatic joint limits as two inequalities d − lo ≥ 0 and hi − d ≥ 0, d = (P_b − P_a)·(R_a
/// axis_a) the displacement of b's point along a's axis (m).
TermPtr PrismaticLimits(const Attachment& a, const Attachment& b, double lo, double hi);
/// A revolute or prismatic joint's coordinate (θ or d) as one row: a design study holds a
/// design joint still with it where the mechanism's mobility is defined (the Dexterity's C).
/// @throws std::invalid_argument for another joint type.
TermPtr JointCoordinate(const std::string& type, const Attachment& a, const Attachment& b);
/// The displacement d of PrismaticLimits (for reports).
double PrismaticDisplacement(const Attachment& a, const Attachment& b,
                             const std::vector<BodyPose>& poses);

}  // namespace tangent::optimizer
