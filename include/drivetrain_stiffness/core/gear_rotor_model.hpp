// The 3-DOF transverse-torsional gear-rotor-bearing model of seed 000 section 3, as derived in
// docs/model.md: state y = [x_p, x_g, x, x_p', x_g', x'] (m, m/s), x = r_p theta_p - r_g theta_g,
// mesh deflection delta = x + x_p - x_g - e(t).
//
// Nonsmooth forces (each a piecewise-linear spring with a damper that never pulls, after
// Modelica's ElastoBacklash: zero force while separated, damper force clipped to
// [-spring, +spring]):
//  - anti-backlash mesh: F = F1 - F2, F1 = drive flank k1 (delta + F_p/k1), F2 = back path
//    k_c (F_p/k_c - delta) (docs/model.md); an ordinary gear: the dead zone of seed 000 eq 17;
//  - bearings: k_r f_b(x) with the radial clearance dead zone of seed 000 eq 17 when u_r > 0; a
//    bilateral linear spring-damper when u_r = 0 (a preloaded bearing).
// No clock is read: time is an argument, and the mesh phase comes from the excitation.
#pragma once

#include <array>
#include <memory>

#include <Eigen/Core>

namespace drivetrain_stiffness {

using State6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

struct GearRotorParameters {
  double pinion_mass = 0.0, gear_mass = 0.0;                ///< m_p, m_g [kg]
  double pinion_inertia = 0.0, gear_inertia = 0.0;          ///< I_p, I_g [kg m^2]
  double pinion_base_radius = 0.0, gear_base_radius = 0.0;  ///< r_p, r_g [m]
  std::array<double, 2> bearing_stiffness{{0.0, 0.0}};      ///< k_r1, k_r2 [N/m]
  std::array<double, 2> bearing_damping{{0.0, 0.0}};        ///< c_b1, c_b2 [N s/m]
  std::array<double, 2> bearing_clearance{{0.0, 0.0}};      ///< radial half-gap u_r [m]
  double mesh_damping = 0.0;                                ///< c_s [N s/m]

  /// Throws InvalidInput naming the field for non-positive masses/inertias/radii or negative
  /// stiffness, damping or clearance.
  void validate() const;
  /// m_s = 1 / (r_p^2 / I_p + r_g^2 / I_g) (seed 000 eq 14) [kg].
  double equivalentMass() const;
};

/// The linear model's 3x3 matrix over (x_p, x_g, x) for a mesh coefficient `mesh` and the bearing
/// coefficients `bearing` (docs/model.md): mesh * [[1,-1,1],[-1,1,-1],[1,-1,1]] + diag(b0, b1, 0).
/// With stiffnesses it is K, with damping coefficients C. One assembly for the modal analysis,
/// the static equilibrium and the scenes.
Eigen::Matrix3d meshBearingMatrix(double mesh, const std::array<double, 2>& bearing);

/// Mesh and load state at one instant, supplied by the excitation.
struct MeshInstant {
  double k_drive = 0.0;        ///< k1 [N/m]
  double k_back = 0.0;         ///< k_c = k_te k2 / (k_te + k2) [N/m]; 0 for an ordinary gear
  double preload_force = 0.0;  ///< F_p [N] (anti-backlash); 0 for an ordinary gear
  double backlash = 0.0;       ///< half gap b [m] of an ordinary gear (seed 000 eq 17)
  double te = 0.0;             ///< static transmission error e [m]
  double te_rate = 0.0;        ///< de/dt [m/s]
  double drive_force = 0.0;    ///< F_m + F_d: m_s (r_p T_p / I_p + r_g T_g / I_g) [N]
  double phase = 0.0;          ///< mesh phase [-]
};

/// The rig's measured motion over one reading interval: mesh phase phi(t) = phase0 + frequency
/// (t - t0) [turns] at a signed mesh frequency [Hz] (0: standing, < 0: reversed).
struct MeshMotion {
  double t0 = 0.0;         ///< [s]
  double phase0 = 0.0;     ///< [turns] at t0, not wrapped
  double frequency = 0.0;  ///< [Hz]
  double phaseAt(double t) const {
    return phase0 + frequency * (t - t0);
  }  ///< [turns], not wrapped
  /// InvalidInput naming the field for a non-finite one.
  void validate() const;
};

/// Supplies MeshInstant as a function of time (torque input, mesh stiffness by phase, TE).
class GearExcitation {
 public:
  virtual ~GearExcitation() = default;
  virtual void at(double t, MeshInstant& out) const = 0;
  /// Next time > t at which the right-hand side jumps (a tooth enters or leaves contact, a torque
  /// step); +inf if never.
  virtual double nextSwitch(double t) const = 0;
};

/// Forces and their regime at a state (which contacts are closed), for event detection.
struct ContactRegime {
  std::array<int, 4> code{{0, 0, 0, 0}};  ///< drive flank, back flank, bearing 1, bearing 2
  bool operator==(const ContactRegime& o) const { return code == o.code; }
  bool operator!=(const ContactRegime& o) const { return !(*this == o); }
};

struct GearRotorForces {
  double mesh = 0.0;                           ///< F on the gear along n [N]
  double drive_flank = 0.0, back_flank = 0.0;  ///< flank forces F1, F2 [N] (anti-backlash)
  double bearing[2] = {0.0, 0.0};
  double delta = 0.0, delta_rate = 0.0;
  double mesh_slope = 0.0, mesh_damping_slope = 0.0;  ///< dF/d(delta), dF/d(delta') in this regime
  double bearing_slope[2] = {0.0, 0.0}, bearing_damping_slope[2] = {0.0, 0.0};
  double drive_force = 0.0;  ///< F_m + F_d at this time [N]
  ContactRegime regime;
};

class RigExcitation;
class SlicedExcitation;

/// The model: its parameters by value, its excitation shared (immutable: every copy of a model sees
/// the same one), and for a rig the torque input. A copy is a whole model of its own.
class GearRotorModel {
 public:
  GearRotorModel(const GearRotorParameters& p, std::shared_ptr<const GearExcitation> excitation);
  /// A rig's model. The exact propagation, the Floquet analysis and the reduced fidelities need the
  /// excitation's mesh frequency, TE and torque profile, which only a rig excitation has: the model
  /// keeps it by its type (rigExcitation()) rather than have them find out by a downcast.
  GearRotorModel(const GearRotorParameters& p, std::shared_ptr<const RigExcitation> excitation);
  /// The same (a shared_ptr<RigExcitation> would otherwise convert to either of the two above).
  GearRotorModel(const GearRotorParameters& p, std::shared_ptr<RigExcitation> excitation);
  /// The sliced mesh along a measured motion (the estimator following the encoders): the motion
  /// and the torque are the model's inputs (setMotionInput, setTorqueInput), not the excitation's.
  GearRotorModel(const GearRotorParameters& p, std::shared_ptr<const SlicedExcitation> excitation);
  GearRotorModel(const GearRotorParameters& p, std::shared_ptr<SlicedExcitation> excitation);

  const GearRotorParameters& parameters() const { return p_; }
  /// New parameters over the same excitation, as GearRotorModel(p, excitation) would have them
  /// (validated first: a refusal changes nothing). No allocation: a bearing-stiffness change on
  /// the per-input path.
  void setParameters(const GearRotorParameters& p);
  const GearExcitation& excitation() const { return *excitation_; }
  /// The rig excitation the model was built on, or null (sliced, constant or test excitations).
  const RigExcitation* rigExcitation() const { return rig_.get(); }
  double equivalentMass() const { return m_s_; }

  /// The pinion torque input u [N·m] of a rig excitation whose torque profile is kInput (the
  /// online estimator's measured torque, held until the next measurement): from now on the drive
  /// force is RigExcitation::driveForce(u). Its owner sets it; nothing else holds it. InvalidInput
  /// for a model without a torque input (its torque is a function of time) or a non-finite u.
  void setTorqueInput(double torque);
  double torqueInput() const {
    return torque_input_;
  }  ///< [N·m]; 0 (a sliced excitation's own) until set
  /// The measured motion input of a model over a SlicedExcitation: from now on the mesh phase is
  /// motion.phaseAt(t). Its owner re-anchors it at each encoder reading. InvalidInput for any
  /// other model or a non-finite field.
  void setMotionInput(const MeshMotion& motion);
  const MeshMotion& motionInput() const { return motion_input_; }
  /// The mesh and load state at t as the model sees it: the excitation's, with the drive force of
  /// the torque input when it takes one. forces(), energy() and the samples read it here.
  void meshAt(double t, MeshInstant& m) const;
  /// The excitation's next switch after t (GearExcitation::nextSwitch), along the motion input
  /// when the model takes one.
  double nextSwitch(double t) const;

  /// y' = f(t, y).
  void rhs(double t, const State6& y, State6& dydt) const;
  /// Forces at (t, y) with their contact regime.
  GearRotorForces forces(double t, const State6& y) const;
  /// d f / d y, consistent with the contact regime at (t, y) (for implicit methods).
  Matrix6 jacobian(double t, const State6& y) const;
  /// Mechanical energy of the 3-DOF system for a linear, clearance-free configuration:
  /// 1/2 (m_p v_p^2 + m_g v_g^2 + m_s v^2) + 1/2 (k_r1 x_p^2 + k_r2 x_g^2 + k_s delta^2),
  /// with k_s = k1 + k_c at time t (docs/model.md "Energy").
  double energy(double t, const State6& y) const;

 private:
  GearRotorParameters p_;
  std::shared_ptr<const GearExcitation> excitation_;
  std::shared_ptr<const RigExcitation>
      rig_;  ///< the same object as excitation_, by type; null if not a rig's
  std::shared_ptr<const SlicedExcitation> sliced_;  ///< the same, by type; null if not sliced
  MeshMotion motion_input_;                         ///< used with sliced_
  double m_s_ = 0.0;
  bool torque_input_used_ = false;  ///< rig_ takes its torque from torque_input_
  double torque_input_ = 0.0;       ///< u [N·m]
};

/// Output samples on a grid that divides the mesh period land exactly on the tooth switch at phase
/// 0, where the mesh stiffness jumps and rounding would pick either side at random. The convention
/// for samples: the right limit. Fills `m` (GearRotorModel::meshAt) at t, or 1e-6 of a mesh period
/// later when t is within 1e-7 of a period of a switch (beyond the phase rounding, ~1e-9 periods
/// after 1e4 s, and far below what the state moves in), and returns the time used. te, te_rate and
/// drive_force, which are continuous, stay those at t.
double meshForSample(const GearRotorModel& model, double t, double interval, MeshInstant& m);

/// Excitation with constant mesh stiffness and load, for tests and the linear limit.
class ConstantExcitation : public GearExcitation {
 public:
  explicit ConstantExcitation(const MeshInstant& m) : m_(m) {}
  void at(double, MeshInstant& out) const override { out = m_; }
  double nextSwitch(double) const override;

 private:
  MeshInstant m_;
};

}  // namespace drivetrain_stiffness
