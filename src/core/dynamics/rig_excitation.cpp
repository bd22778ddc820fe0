#include "drivetrain_stiffness/core/dynamics/rig_excitation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
void TorqueProfile::retune(double new_frequency, double t) {
  phase = std::remainder(kTwoPi * (frequency - new_frequency) * t + phase, kTwoPi);
  frequency = new_frequency;
}

double TorqueProfile::at(double t) const {
  switch (kind) {
    case Kind::kConstant: return mean;
    case Kind::kSine: return mean + amplitude * std::sin(kTwoPi * frequency * t + phase);
    case Kind::kSteps: {
      double torque = mean;
      for (const auto& s : steps) {
        if (t >= s.first) torque = s.second;
      }
      return torque;
    }
    case Kind::kChirp: {
      // Linear chirp: instantaneous frequency f0 + (f1 - f0) t / T, phase 2 pi (f0 t + (f1 - f0)
      // t^2 / 2T).
      const double tt = std::min(t, chirp_duration);
      const double phase =
          kTwoPi * (chirp_start * tt + 0.5 * (chirp_end - chirp_start) * tt * tt / chirp_duration) +
          kTwoPi * chirp_end * std::max(0.0, t - chirp_duration);
      return mean + amplitude * std::sin(phase);
    }
    case Kind::kInput: return 0.0;  // the model adds its input (RigExcitation::driveForce)
  }
  return mean;
}

void TorqueProfile::validate() const {
  requireFinite("torque.mean", mean);
  requireFinite("torque.amplitude", amplitude);
  requireNonNegative("torque.frequency", frequency);
  requireNonNegative("torque.chirp_start", chirp_start);
  requireNonNegative("torque.chirp_end", chirp_end);
  requirePositive("torque.chirp_duration", chirp_duration);
  double last = -INFINITY;
  for (const auto& s : steps) {
    requireFinite("torque.steps.time", s.first);
    requireFinite("torque.steps.torque", s.second);
    if (!(s.first > last)) throwInvalid("torque.steps.time", s.first, "step times must increase");
    last = s.first;
  }
}

RigExcitation::RigExcitation(std::shared_ptr<const AntiBacklashMesh> mesh,
                             const GearRotorParameters& params, const RigExcitationSpec& spec)
    : mesh_(std::move(mesh)), spec_(spec) {
  if (!mesh_) throw InvalidInput("mesh: missing");
  params.validate();
  spec.torque.validate();
  requirePositive("speed", spec.speed);
  requireFinite("initial_phase", spec.initial_phase);
  requireNonNegative("transmission_error_amplitude", spec.te_amplitude);
  requireNonNegative("backlash", spec.backlash);
  mesh_frequency_ = spec.speed * mesh_->geometry().spec().teeth[0] / kTwoPi;
  m_s_ = params.equivalentMass();
  if (spec.balanced_load) {
    // m_s (r_p T_p / I_p + r_g T_g / I_g) with T_g = T_p r_g / r_p equals T_p / r_p
    // (docs/model.md).
    torque_gain_ = 1.0 / params.pinion_base_radius;
    load_term_ = 0.0;
  } else {
    torque_gain_ = m_s_ * params.pinion_base_radius / params.pinion_inertia;
    // Load torque balancing the mean input: T_g = T_pm r_g / r_p (docs/model.md); its term
    // m_s r_g T_g / I_g in the drive force is constant.
    const double t_g = spec.torque.mean * params.gear_base_radius / params.pinion_base_radius;
    load_term_ = m_s_ * params.gear_base_radius * t_g / params.gear_inertia;
  }
  switches_ = mesh_->switchingPhases();
}

void RigExcitation::at(double t, MeshInstant& out) const {
  const double turns = spec_.initial_phase + mesh_frequency_ * t;
  const double whole = std::floor(turns);
  out.phase = turns - whole;
  const CompositeMesh c = mesh_->at(out.phase, 0.0);
  out.k_drive = c.k1;
  out.k_back = mesh_->spec().spring_stiffness > 0.0 ? c.k_chain : 0.0;
  out.preload_force = mesh_->preloadForce();
  out.backlash = spec_.backlash;
  const double w = kTwoPi * mesh_frequency_;
  out.te = spec_.te_amplitude * std::sin(w * t + kTwoPi * spec_.initial_phase);
  out.te_rate = spec_.te_amplitude * w * std::cos(w * t + kTwoPi * spec_.initial_phase);
  out.drive_force = driveForce(spec_.torque.at(t));
}

double RigExcitation::nextSwitch(double t) const {
  const double turns = spec_.initial_phase + mesh_frequency_ * t;
  const double whole = std::floor(turns), phase = turns - whole;
  double next = whole + 1.0 + (switches_.empty() ? 0.0 : switches_.front());
  for (double s : switches_) {
    if (s > phase) {
      next = whole + s;
      break;
    }  // however close: a skipped switch would be straddled
  }
  double time = (next - spec_.initial_phase) / mesh_frequency_;
  // Torque steps are switches of the right-hand side too.
  if (spec_.torque.kind == TorqueProfile::Kind::kSteps) {
    for (const auto& s : spec_.torque.steps) {
      if (s.first > t * (1.0 + 1e-15) + 1e-300 && s.first < time) {
        time = s.first;
        break;
      }
    }
  }
  return time > t ? time : std::nextafter(t, std::numeric_limits<double>::infinity());
}

}  // namespace drivetrain_stiffness
