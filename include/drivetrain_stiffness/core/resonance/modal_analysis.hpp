// Resonance estimates of the 3-DOF model: modes at an operating point and Floquet stability over a
// mesh period (docs/resonance.md "Estimates").
#pragma once

#include <array>
#include <complex>
#include <string>

#include <Eigen/Core>

#include "drivetrain_stiffness/core/dynamics/gear_rotor_model.hpp"

namespace drivetrain_stiffness {

struct Mode {
  double natural_frequency = 0.0;                   ///< undamped [Hz]
  double damped_frequency = 0.0;                    ///< [Hz]
  double damping_ratio = 0.0;                       ///< [-]
  std::string dominant;                             ///< "x_p", "x_g" or "x"
  Eigen::Vector3d shape = Eigen::Vector3d::Zero();  ///< mass-normalised, largest entry positive
};

/// The modes of the linearised model at mesh stiffness k_s [N/m], by natural frequency: K v = w^2
/// M v and the eigenvalues of [[0, I], [-M^-1 K, -M^-1 C]] (docs/model.md "Linearisation").
std::array<Mode, 3> modalAnalysis(const GearRotorParameters& p, double mesh_stiffness);

struct FloquetResult {
  Eigen::Matrix<std::complex<double>, 6, 1> multipliers;
  double max_modulus = 0.0;
  double margin = 0.0;  ///< 1 - max |mu|: > 0 stable
};

/// The Floquet multipliers about y_ref (contacts closed) over `period` [s] from t0 [s]: the exact
/// propagators for a RigExcitation, else RK4 with `steps` steps.
FloquetResult floquet(const GearRotorModel& model, const State6& y_ref, double t0, double period,
                      int steps = 4000);

}  // namespace drivetrain_stiffness
