#include "drivetrain_stiffness/core/dynamics/gear_rotor_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "drivetrain_stiffness/core/dynamics/rig_excitation.hpp"
#include "drivetrain_stiffness/core/gear/sliced_mesh.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

Eigen::Matrix3d meshBearingMatrix(double mesh, const std::array<double, 2>& bearing) {
  Eigen::Matrix3d m;
  m << 1, -1, 1, -1, 1, -1, 1, -1, 1;
  m *= mesh;
  m(0, 0) += bearing[0];
  m(1, 1) += bearing[1];
  return m;
}
namespace {

// A compressive contact: spring force s = k g for g > 0 (g the penetration), damper c g' clipped so
// the total stays in [0, 2 s] (never pulls, never more than doubles the spring force: Modelica
// ElastoBacklash). Returns the force and, through the pointers, d(force)/dg and d(force)/dg'.
double contact(double k, double c, double g, double g_rate, double* dk, double* dc, int* closed) {
  if (!(g > 0.0) || k <= 0.0) {
    *dk = *dc = 0.0;
    *closed = 0;
    return 0.0;
  }
  *closed = 1;
  const double spring = k * g;
  const double total = spring + c * g_rate;
  if (total < 0.0) {
    *dk = *dc = 0.0;
    return 0.0;
  }
  if (total > 2.0 * spring) {
    *dk = 2.0 * k;
    *dc = 0.0;
    return 2.0 * spring;
  }
  *dk = k;
  *dc = c;
  return total;
}

}  // namespace

void GearRotorParameters::validate() const {
  requirePositive("dynamics.pinion_mass", pinion_mass);
  requirePositive("dynamics.gear_mass", gear_mass);
  requirePositive("dynamics.pinion_inertia", pinion_inertia);
  requirePositive("dynamics.gear_inertia", gear_inertia);
  requirePositive("dynamics.pinion_base_radius", pinion_base_radius);
  requirePositive("dynamics.gear_base_radius", gear_base_radius);
  // Literal names: the modal analysis validates on every call, and a built name would allocate.
  static constexpr const char* kStiffness[2] = {"dynamics.bearing_stiffness[0]",
                                                "dynamics.bearing_stiffness[1]"};
  static constexpr const char* kDamping[2] = {"dynamics.bearing_damping[0]",
                                              "dynamics.bearing_damping[1]"};
  static constexpr const char* kClearance[2] = {"dynamics.bearing_clearance[0]",
                                                "dynamics.bearing_clearance[1]"};
  for (int i = 0; i < 2; ++i) {
    requireNonNegative(kStiffness[i], bearing_stiffness[i]);
    requireNonNegative(kDamping[i], bearing_damping[i]);
    requireNonNegative(kClearance[i], bearing_clearance[i]);
  }
  requireNonNegative("dynamics.mesh_damping", mesh_damping);
}

double GearRotorParameters::equivalentMass() const {
  return 1.0 / (pinion_base_radius * pinion_base_radius / pinion_inertia +
                gear_base_radius * gear_base_radius / gear_inertia);
}

void MeshMotion::validate() const {
  requireFinite("t0", t0);
  requireFinite("mesh phase", phase0);
  requireFinite("mesh frequency", frequency);
}

double ConstantExcitation::nextSwitch(double) const {
  return std::numeric_limits<double>::infinity();
}

GearRotorModel::GearRotorModel(const GearRotorParameters& p,
                               std::shared_ptr<const GearExcitation> excitation)
    : p_(p), excitation_(std::move(excitation)) {
  p_.validate();
  if (!excitation_) throw InvalidInput("excitation: missing");
  m_s_ = p_.equivalentMass();
}

GearRotorModel::GearRotorModel(const GearRotorParameters& p,
                               std::shared_ptr<const RigExcitation> excitation)
    : GearRotorModel(p, std::shared_ptr<const GearExcitation>(excitation)) {
  rig_ = std::move(excitation);
  torque_input_used_ = rig_->takesTorqueInput();
}

GearRotorModel::GearRotorModel(const GearRotorParameters& p,
                               std::shared_ptr<RigExcitation> excitation)
    : GearRotorModel(p, std::shared_ptr<const RigExcitation>(std::move(excitation))) {}

GearRotorModel::GearRotorModel(const GearRotorParameters& p,
                               std::shared_ptr<const SlicedExcitation> excitation)
    : GearRotorModel(p, std::shared_ptr<const GearExcitation>(excitation)) {
  sliced_ = std::move(excitation);
  torque_input_used_ = true;
  motion_input_ = sliced_->motion();
  torque_input_ = sliced_->torque();
}

GearRotorModel::GearRotorModel(const GearRotorParameters& p,
                               std::shared_ptr<SlicedExcitation> excitation)
    : GearRotorModel(p, std::shared_ptr<const SlicedExcitation>(std::move(excitation))) {}

void GearRotorModel::setMotionInput(const MeshMotion& motion) {
  if (!sliced_)
    throw InvalidInput("motion input: the model's excitation has a mesh phase of its own");
  motion.validate();
  motion_input_ = motion;
}

double GearRotorModel::nextSwitch(double t) const {
  return sliced_ ? sliced_->nextSwitch(t, motion_input_) : excitation_->nextSwitch(t);
}

void GearRotorModel::setTorqueInput(double torque) {
  if (!torque_input_used_)
    throw InvalidInput("torque input: the model's excitation has a torque profile of its own");
  requireFinite("torque", torque);
  torque_input_ = torque;
}

void GearRotorModel::meshAt(double t, MeshInstant& m) const {
  if (sliced_) {
    sliced_->at(t, motion_input_, torque_input_, m);
    return;
  }
  excitation_->at(t, m);
  if (torque_input_used_) m.drive_force = rig_->driveForce(torque_input_);
}

void GearRotorModel::setParameters(const GearRotorParameters& p) {
  p.validate();
  p_ = p;
  m_s_ = p_.equivalentMass();
}

GearRotorForces GearRotorModel::forces(double t, const State6& y) const {
  MeshInstant m;
  meshAt(t, m);
  GearRotorForces f;
  f.delta = y[2] + y[0] - y[1] - m.te;
  f.delta_rate = y[5] + y[3] - y[4] - m.te_rate;
  double dk, dc;
  const double k_sum = m.k_drive + m.k_back;
  if (m.k_back > 0.0 || m.preload_force > 0.0) {
    // Anti-backlash: drive flank penetration g1 = delta + F_p/k1, back path g2 = F_p/k_c - delta.
    // Mesh damping shared in proportion to the flank stiffness.
    const double c1 = k_sum > 0.0 ? p_.mesh_damping * m.k_drive / k_sum : 0.0;
    const double c2 = p_.mesh_damping - c1;
    const double g1 = m.k_drive > 0.0 ? f.delta + m.preload_force / m.k_drive : -1.0;
    const double g2 = m.k_back > 0.0 ? m.preload_force / m.k_back - f.delta : -1.0;
    f.drive_flank = contact(m.k_drive, c1, g1, f.delta_rate, &dk, &dc, &f.regime.code[0]);
    f.mesh_slope = dk;
    f.mesh_damping_slope = dc;
    f.back_flank = contact(m.k_back, c2, g2, -f.delta_rate, &dk, &dc, &f.regime.code[1]);
  } else {
    // Ordinary gear with backlash b (seed 000 eq 17): drive flank for delta > b, back flank for
    // delta < -b.
    f.drive_flank = contact(m.k_drive, p_.mesh_damping, f.delta - m.backlash, f.delta_rate, &dk,
                            &dc, &f.regime.code[0]);
    f.mesh_slope = dk;
    f.mesh_damping_slope = dc;
    f.back_flank = contact(m.k_drive, p_.mesh_damping, -f.delta - m.backlash, -f.delta_rate, &dk,
                           &dc, &f.regime.code[1]);
  }
  // F = F1 - F2 with g2 decreasing in delta: both slopes add.
  f.mesh = f.drive_flank - f.back_flank;
  f.mesh_slope += dk;
  f.mesh_damping_slope += dc;
  f.drive_force = m.drive_force;
  for (int i = 0; i < 2; ++i) {
    const double x = y[i], v = y[3 + i], u = p_.bearing_clearance[i];
    const double k = p_.bearing_stiffness[i], c = p_.bearing_damping[i];
    if (u == 0.0) {
      // No clearance: a preloaded bearing is a bilateral spring-damper (balls loaded all round).
      f.bearing[i] = k * x + c * v;
      f.bearing_slope[i] = k;
      f.bearing_damping_slope[i] = c;
      f.regime.code[2 + i] = 0;
      continue;
    }
    int plus = 0, minus = 0;
    double dk2, dc2;
    const double fp = contact(k, c, x - u, v, &dk, &dc, &plus);
    const double fm = contact(k, c, -x - u, -v, &dk2, &dc2, &minus);
    f.bearing[i] = fp - fm;  // restoring force on the shaft is -bearing[i]
    f.bearing_slope[i] = dk + dk2;
    f.bearing_damping_slope[i] = dc + dc2;
    f.regime.code[2 + i] = plus - minus;
  }
  return f;
}

void GearRotorModel::rhs(double t, const State6& y, State6& dydt) const {
  const GearRotorForces f = forces(t, y);
  dydt[0] = y[3];
  dydt[1] = y[4];
  dydt[2] = y[5];
  dydt[3] = (-f.bearing[0] - f.mesh) / p_.pinion_mass;
  dydt[4] = (-f.bearing[1] + f.mesh) / p_.gear_mass;
  dydt[5] = (f.drive_force - f.mesh) / m_s_;
}

Matrix6 GearRotorModel::jacobian(double t, const State6& y) const {
  // Exact inside the contact regime at (t, y): the forces are piecewise linear in (delta, delta')
  // and (x_b, x_b'), with delta = x + x_p - x_g - e.
  const GearRotorForces f = forces(t, y);
  Matrix6 j = Matrix6::Zero();
  j(0, 3) = j(1, 4) = j(2, 5) = 1.0;
  const Eigen::Vector3d d_delta(1.0, -1.0, 1.0);  // d delta / d (x_p, x_g, x)
  const Eigen::Vector3d inv_m(1.0 / p_.pinion_mass, 1.0 / p_.gear_mass, 1.0 / m_s_);
  const Eigen::Vector3d sign(-1.0, 1.0, -1.0);  // mesh force enters pinion -, gear +, x -
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      j(3 + r, c) = sign[r] * f.mesh_slope * d_delta[c] * inv_m[r];
      j(3 + r, 3 + c) = sign[r] * f.mesh_damping_slope * d_delta[c] * inv_m[r];
    }
  }
  for (int i = 0; i < 2; ++i) {
    j(3 + i, i) -= f.bearing_slope[i] * inv_m[i];
    j(3 + i, 3 + i) -= f.bearing_damping_slope[i] * inv_m[i];
  }
  return j;
}

double GearRotorModel::energy(double t, const State6& y) const {
  MeshInstant m;
  meshAt(t, m);
  const double delta = y[2] + y[0] - y[1] - m.te;
  const double ks = m.k_drive + m.k_back;
  return 0.5 * (p_.pinion_mass * y[3] * y[3] + p_.gear_mass * y[4] * y[4] + m_s_ * y[5] * y[5]) +
         0.5 * (p_.bearing_stiffness[0] * y[0] * y[0] + p_.bearing_stiffness[1] * y[1] * y[1] +
                ks * delta * delta);
}

double meshForSample(const GearRotorModel& model, double t, double interval, MeshInstant& m) {
  model.meshAt(t, m);
  if (std::min(m.phase, 1.0 - m.phase) >= 1e-7) return t;
  const MeshInstant at_t = m;
  // Step 1e-6 of a mesh period past the switch (the phase rate from one interval ahead), so the
  // step stays well above the phase rounding at any output rate.
  MeshInstant ahead;
  model.meshAt(t + interval, ahead);
  const double advance = std::fmod(ahead.phase - at_t.phase + 2.0, 1.0);  // periods per interval
  const double after = t + (advance > 1e-9 ? 1e-6 / advance : 1e-6) * interval;
  model.meshAt(after, m);
  // Only the stiffness side changes; the continuous inputs stay those at t.
  m.te = at_t.te;
  m.te_rate = at_t.te_rate;
  m.drive_force = at_t.drive_force;
  return after;
}

}  // namespace drivetrain_stiffness
