// Excitation of the gear-rotor model from the rig: pinion torque input (constant, sine, steps,
// chirp), the mean load torque that balances it, the anti-backlash mesh stiffness looked up by
// mesh phase (pinion turning at a nominal speed), and a manufacturing transmission error at the
// mesh frequency. Tooth-count switches are reported as exact time events.
#pragma once

#include <memory>
#include <utility>
#include <vector>

#include "drivetrain_stiffness/core/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/gear_rotor_model.hpp"

namespace drivetrain_stiffness {

/// Pinion input torque T_p(t) [N·m]: a function of time, or (kInput) the model's torque input.
struct TorqueProfile {
  /// kInput: no torque of its own; the torque is the input of the model built on the excitation
  /// (GearRotorModel::setTorqueInput: the online estimator's measured torque, held until the next
  /// measurement), given by whoever owns that model rather than read from a shared value.
  enum class Kind { kConstant, kSine, kSteps, kChirp, kInput };
  Kind kind = Kind::kConstant;
  double mean = 0.0;       ///< [N·m]; also sets the balancing load torque T_g = mean r_g / r_p
  double amplitude = 0.0;  ///< sine / chirp amplitude [N·m]
  double frequency = 0.0;  ///< sine frequency [Hz]
  double phase = 0.0;  ///< sine phase at t = 0 [rad] (a stepped sweep keeps the sine continuous)
  double chirp_start = 0.0, chirp_end = 0.0, chirp_duration = 1.0;  ///< linear chirp [Hz, Hz, s]
  std::vector<std::pair<double, double>> steps;  ///< (time [s], torque [N·m]) from that time on
  /// The torque at t; 0 for kInput (the model adds its input: RigExcitation::driveForce).
  double at(double t) const;
  /// Validates the numbers (finite, non-negative frequencies, ordered steps); names the field.
  void validate() const;
  /// Switches a sine to `new_frequency` at time t keeping the torque continuous there:
  /// 2 pi f_new t + phi_new = 2 pi f_old t + phi_old (mod 2 pi). Used by stepped sweeps.
  void retune(double new_frequency, double t);
};

struct RigExcitationSpec {
  double speed = 0.0;          ///< pinion speed [rad/s] (sets the mesh phase)
  double initial_phase = 0.0;  ///< mesh phase at t = 0
  double te_amplitude = 0.0;   ///< manufacturing TE amplitude at the mesh frequency [m]
  double backlash = 0.0;       ///< half backlash of an ordinary gear [m] (seed 000 eq 17 b)
  /// false: the load torque is fixed at the mean input (T_g = T_pm r_g / r_p) and fluctuations act
  /// on the pinion alone (scenes). true: the load follows the input quasi-statically (a
  /// speed-controlled rig), so the drive force is T_p / r_p (the live node).
  bool balanced_load = false;
  TorqueProfile torque;
};

class RigExcitation : public GearExcitation {
 public:
  RigExcitation(std::shared_ptr<const AntiBacklashMesh> mesh, const GearRotorParameters& params,
                const RigExcitationSpec& spec);
  /// The drive force of the torque profile at t; with a kInput profile that of no torque (the model
  /// over this excitation puts its torque input in: GearRotorModel::meshAt).
  void at(double t, MeshInstant& out) const override;
  double nextSwitch(double t) const override;
  double meshFrequency() const { return mesh_frequency_; }  ///< [Hz]
  /// d(drive force)/d(pinion torque) [1/m]: m_s r_p / I_p, or 1 / r_p with a balanced load.
  double torqueGain() const { return torque_gain_; }
  /// Drive force F_m + F_d [N] at pinion torque T [N·m]: torqueGain() T plus the load's constant
  /// term (seed 000 eq 14 as docs/model.md corrects it: T / r_p with a balanced load).
  double driveForce(double torque) const { return torque_gain_ * torque + load_term_; }
  /// The torque comes from the model's input (TorqueProfile::Kind::kInput), not from time.
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
