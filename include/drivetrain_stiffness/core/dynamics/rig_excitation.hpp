// The rig's excitation of the gear-rotor model: pinion torque, balancing load, the anti-backlash
// mesh stiffness by phase at a nominal speed and the manufacturing TE; tooth switches as time
// events.
#pragma once

#include <memory>
#include <utility>
#include <vector>

#include "drivetrain_stiffness/core/gear/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/dynamics/gear_rotor_model.hpp"

namespace drivetrain_stiffness {

/// The pinion torque T_p(t) [N·m], or (kInput) the model's torque input (setTorqueInput).
struct TorqueProfile {
  enum class Kind { kConstant, kSine, kSteps, kChirp, kInput };
  Kind kind = Kind::kConstant;
  double mean = 0.0;       ///< [N·m]; the load torque T_g = mean r_g / r_p
  double amplitude = 0.0;  ///< [N·m] sine, chirp
  double frequency = 0.0;  ///< [Hz] sine
  double phase = 0.0;      ///< [rad] sine, at t = 0
  double chirp_start = 0.0, chirp_end = 0.0, chirp_duration = 1.0;  ///< [Hz, Hz, s]
  std::vector<std::pair<double, double>> steps;  ///< (time [s], torque [N·m]) from then on
  /// The torque [N·m] at t [s]; 0 for kInput.
  double at(double t) const;
  /// Throws InvalidInput naming a non-finite value, a negative frequency or unordered steps.
  void validate() const;
  /// A sine retuned to `new_frequency` [Hz] at t [s] with the torque continuous:
  /// 2 pi f_new t + phi_new = 2 pi f_old t + phi_old (mod 2 pi).
  void retune(double new_frequency, double t);
};

struct RigExcitationSpec {
  double speed = 0.0;          ///< [rad/s] pinion
  double initial_phase = 0.0;  ///< [-] at t = 0
  double te_amplitude = 0.0;   ///< [m] at the mesh frequency
  double backlash = 0.0;       ///< [m] half, ordinary gear (seed 000 eq 17 b)
  /// true: the load follows the input (drive force T_p / r_p, the live node); false: the load is
  /// fixed at the mean input and fluctuations act on the pinion alone (scenes).
  bool balanced_load = false;
  TorqueProfile torque;
};

class RigExcitation : public GearExcitation {
 public:
  RigExcitation(std::shared_ptr<const AntiBacklashMesh> mesh, const GearRotorParameters& params,
                const RigExcitationSpec& spec);
  /// The mesh and load at t [s]; a kInput profile contributes no torque.
  void at(double t, MeshInstant& out) const override;
  double nextSwitch(double t) const override;
  double meshFrequency() const { return mesh_frequency_; }  ///< [Hz]
  /// [1/m] m_s r_p / I_p, or 1 / r_p with a balanced load.
  double torqueGain() const { return torque_gain_; }
  /// F_m + F_d [N] at pinion torque T [N·m] (seed 000 eq 14 as docs/model.md "Equations" corrects
  /// it).
  double driveForce(double torque) const { return torque_gain_ * torque + load_term_; }
  bool takesTorqueInput() const { return spec_.torque.kind == TorqueProfile::Kind::kInput; }
  const AntiBacklashMesh& mesh() const { return *mesh_; }
  const RigExcitationSpec& spec() const { return spec_; }

 private:
  std::shared_ptr<const AntiBacklashMesh> mesh_;
  RigExcitationSpec spec_;
  double mesh_frequency_ = 0.0, torque_gain_ = 0.0, load_term_ = 0.0, m_s_ = 0.0;
  std::vector<double> switches_;
};

}  // namespace drivetrain_stiffness
