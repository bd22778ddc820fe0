// The 3-DOF transverse-torsional gear-rotor-bearing model of seed 000 section 3: docs/model.md.
// State y = [x_p, x_g, x, x_p', x_g', x'] [m, m/s]; delta = x + x_p - x_g - e(t).
#pragma once

#include <array>
#include <memory>

#include <Eigen/Core>

namespace drivetrain_stiffness {

using State6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

struct GearRotorParameters {
  double pinion_mass = 0.0, gear_mass = 0.0;                ///< [kg]
  double pinion_inertia = 0.0, gear_inertia = 0.0;          ///< [kg m^2]
  double pinion_base_radius = 0.0, gear_base_radius = 0.0;  ///< [m]
  std::array<double, 2> bearing_stiffness{{0.0, 0.0}};      ///< [N/m]
  std::array<double, 2> bearing_damping{{0.0, 0.0}};        ///< [N s/m]
  std::array<double, 2> bearing_clearance{{0.0, 0.0}};      ///< [m] radial half-gap
  double mesh_damping = 0.0;                                ///< [N s/m]

  /// Throws InvalidInput naming the field unless masses, inertias and radii are positive and the
  /// rest non-negative.
  void validate() const;
  /// m_s = 1 / (r_p^2 / I_p + r_g^2 / I_g) [kg] (seed 000 eq 14).
  double equivalentMass() const;
};

/// K (or C) over (x_p, x_g, x): mesh [[1,-1,1],[-1,1,-1],[1,-1,1]] + diag(b0, b1, 0).
Eigen::Matrix3d meshBearingMatrix(double mesh, const std::array<double, 2>& bearing);

/// The mesh and load at one instant.
struct MeshInstant {
  double k_drive = 0.0;        ///< k1 [N/m]
  double k_back = 0.0;         ///< k_c [N/m]; 0 for an ordinary gear
  double preload_force = 0.0;  ///< F_p [N]; 0 for an ordinary gear
  double backlash = 0.0;       ///< b [m], ordinary gear (seed 000 eq 17)
  double te = 0.0;             ///< e [m]
  double te_rate = 0.0;        ///< [m/s]
  double drive_force = 0.0;    ///< F_m + F_d [N] (seed 000 eq 14)
  double phase = 0.0;          ///< [-]
};

/// The measured motion over one reading interval: phi(t) = phase0 + frequency (t - t0) [turns].
struct MeshMotion {
  double t0 = 0.0;         ///< [s]
  double phase0 = 0.0;     ///< [turns] at t0, not wrapped
  double frequency = 0.0;  ///< [Hz], signed
  double phaseAt(double t) const {
    return phase0 + frequency * (t - t0);
  }  ///< [turns], not wrapped
  /// Throws InvalidInput naming a non-finite field.
  void validate() const;
};

/// MeshInstant as a function of time.
class GearExcitation {
 public:
  virtual ~GearExcitation() = default;
  virtual void at(double t, MeshInstant& out) const = 0;
  /// The next time > t [s] at which the right-hand side jumps; +inf if never.
  virtual double nextSwitch(double t) const = 0;
};

/// Which contacts are closed, for event detection.
struct ContactRegime {
  std::array<int, 4> code{{0, 0, 0, 0}};  ///< drive flank, back flank, bearing 1, bearing 2
  bool operator==(const ContactRegime& o) const { return code == o.code; }
  bool operator!=(const ContactRegime& o) const { return !(*this == o); }
};

struct GearRotorForces {
  double mesh = 0.0;                           ///< [N] on the gear along n
  double drive_flank = 0.0, back_flank = 0.0;  ///< [N] F1, F2
  double bearing[2] = {0.0, 0.0};
  double delta = 0.0, delta_rate = 0.0;
  double mesh_slope = 0.0, mesh_damping_slope = 0.0;  ///< dF/d(delta), dF/d(delta')
  double bearing_slope[2] = {0.0, 0.0}, bearing_damping_slope[2] = {0.0, 0.0};
  double drive_force = 0.0;  ///< [N]
  ContactRegime regime;
};

class RigExcitation;
class SlicedExcitation;

/// The model: parameters by value, the excitation shared and immutable.
class GearRotorModel {
 public:
  GearRotorModel(const GearRotorParameters& p, std::shared_ptr<const GearExcitation> excitation);
  /// A rig's model, its excitation kept by type (rigExcitation()).
  GearRotorModel(const GearRotorParameters& p, std::shared_ptr<const RigExcitation> excitation);
  GearRotorModel(const GearRotorParameters& p, std::shared_ptr<RigExcitation> excitation);
  /// The sliced mesh along a measured motion: motion and torque are inputs (setMotionInput,
  /// setTorqueInput).
  GearRotorModel(const GearRotorParameters& p, std::shared_ptr<const SlicedExcitation> excitation);
  GearRotorModel(const GearRotorParameters& p, std::shared_ptr<SlicedExcitation> excitation);

  const GearRotorParameters& parameters() const { return p_; }
  /// New parameters over the same excitation; validated first (a refusal changes nothing).
  /// Allocation-free.
  void setParameters(const GearRotorParameters& p);
  const GearExcitation& excitation() const { return *excitation_; }
  /// The rig excitation, or null.
  const RigExcitation* rigExcitation() const { return rig_.get(); }
  double equivalentMass() const { return m_s_; }

  /// The pinion torque input u [N·m], held: the drive force is RigExcitation::driveForce(u) from
  /// now on. Throws InvalidInput for a model without a torque input or a non-finite u.
  void setTorqueInput(double torque);
  double torqueInput() const { return torque_input_; }  ///< [N·m]; 0 until set
  /// The mesh phase is motion.phaseAt(t) from now on. Throws InvalidInput for a model not over a
  /// SlicedExcitation or a non-finite field.
  void setMotionInput(const MeshMotion& motion);
  const MeshMotion& motionInput() const { return motion_input_; }
  /// The mesh and load at t [s], with the torque input's drive force when it takes one.
  void meshAt(double t, MeshInstant& m) const;
  /// The excitation's next switch after t [s], along the motion input if any.
  double nextSwitch(double t) const;

  /// y' = f(t, y).
  void rhs(double t, const State6& y, State6& dydt) const;
  /// The forces at (t, y) and their contact regime.
  GearRotorForces forces(double t, const State6& y) const;
  /// d f / d y in the contact regime at (t, y).
  Matrix6 jacobian(double t, const State6& y) const;
  /// The mechanical energy [J] of a linear, clearance-free configuration, k_s = k1 + k_c at t
  /// (docs/model.md "Energy").
  double energy(double t, const State6& y) const;

 private:
  GearRotorParameters p_;
  std::shared_ptr<const GearExcitation> excitation_;
  std::shared_ptr<const RigExcitation> rig_;        ///< excitation_ by type, or null
  std::shared_ptr<const SlicedExcitation> sliced_;  ///< excitation_ by type, or null
  MeshMotion motion_input_;                         ///< with sliced_
  double m_s_ = 0.0;
  bool torque_input_used_ = false;  ///< rig_ takes its torque from torque_input_
  double torque_input_ = 0.0;       ///< u [N·m]
};

/// meshAt for an output sample, as the right limit at a tooth switch: at t [s], or 1e-6 of a mesh
/// period later within 1e-7 of a period of a switch (te, te_rate and drive_force stay t's). Returns
/// the time used.
double meshForSample(const GearRotorModel& model, double t, double interval, MeshInstant& m);

/// Constant mesh stiffness and load (tests, the linear limit).
class ConstantExcitation : public GearExcitation {
 public:
  explicit ConstantExcitation(const MeshInstant& m) : m_(m) {}
  void at(double, MeshInstant& out) const override { out = m_; }
  double nextSwitch(double) const override;

 private:
  MeshInstant m_;
};

}  // namespace drivetrain_stiffness
