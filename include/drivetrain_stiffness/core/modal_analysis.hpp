// Resonance estimates of the 3-DOF model (issue 5): modal analysis of the linearised system at an
// operating point and Floquet stability of the mesh-periodic system.
//
//  - modes: K v = w^2 M v with the matrices of docs/model.md (undamped natural frequencies, mass-
//    normalised shapes), and the eigenvalues lambda of the 6x6 state matrix [[0, I], [-M^-1 K,
//    -M^-1 C]] (damped frequency |Im lambda| / 2 pi, damping ratio -Re lambda / |lambda|). Each
//    mode is labelled by the coordinate holding most of its kinetic energy (m_i |v_i|^2).
//  - Floquet: the monodromy matrix Phi(T) of the homogeneous linearised system over one mesh
//    period T; the system is asymptotically stable iff every multiplier |mu| < 1. The margin
//    1 - max |mu| is positive when stable, negative when a parametric resonance grows.
#pragma once

#include <array>
#include <complex>
#include <string>

#include <Eigen/Core>

#include "drivetrain_stiffness/core/gear_rotor_model.hpp"

namespace drivetrain_stiffness {

struct Mode {
  double natural_frequency = 0.0;                   ///< undamped [Hz]
  double damped_frequency = 0.0;                    ///< [Hz]
  double damping_ratio = 0.0;                       ///< [-]
  std::string dominant;                             ///< "x_p", "x_g" or "x"
  Eigen::Vector3d shape = Eigen::Vector3d::Zero();  ///< mass-normalised, largest entry positive
};

/// Modes of the linearised model with mesh stiffness k_s and mesh damping c_s (the parameters'
/// bearing stiffness and damping), sorted by natural frequency.
std::array<Mode, 3> modalAnalysis(const GearRotorParameters& p, double mesh_stiffness);

struct FloquetResult {
  Eigen::Matrix<std::complex<double>, 6, 1> multipliers;
  double max_modulus = 0.0;
  double margin = 0.0;  ///< 1 - max |mu|
};

/// Floquet multipliers of the model linearised about y_ref (contacts closed), over `period` from
/// t0: for a RigExcitation the exact product of the exponential propagators (output_interval must
/// divide the period), otherwise classical RK4 on Phi' = J(t) Phi with `steps` steps.
FloquetResult floquet(const GearRotorModel& model, const State6& y_ref, double t0, double period,
                      int steps = 4000);

}  // namespace drivetrain_stiffness
