// One step of the sliced model's exact solution inside a slice: the modal set-up from a state,
// the state after any length, and a bound on the contact rules over the step (docs/model.md
// "Following the rig's motion"). A part of SlicedModalPropagator.
#pragma once

#include <array>

#include "drivetrain_stiffness/core/dynamics/sliced_slice_tables.hpp"

namespace drivetrain_stiffness {
namespace sliced {

/// One step's modal set-up from y in slice j, independent of its length.
struct Piece {
  int n = 0;
  std::array<int, 6> k{};
  std::array<Complex, 6> eta0{}, force_p{}, force_q{}, force_g{}, pf{}, qf{}, gf{}, r0{};
  std::array<double, 6> n1{}, n2{}, nl{};  ///< |iw - lambda|^2, |-iw - lambda|^2, |lambda|^2
  std::array<bool, 6> particular{};
};

/// Sets out up from y in slice s (regime r, slice j) at TE phasor e_theta0 = e^{i theta}, angular
/// mesh frequency w [rad/s], drive force [N].
void prepare(const ContactRules& rules, const Slice& s, MeshRegime r, int j, const State6& y,
             Complex e_theta0, double w, double drive_force, Piece& out);
/// y over h [s] from the prepared piece, given e_mu = e^{i w h}.
void advance(const Slice& s, const Piece& piece, double w, double h, Complex e_mu, State6& y);
/// Lower bound of regime r's rules over the step: > 0 proves r holds through it.
double regimeMargin(const ContactRules& rules, const Slice& s, MeshRegime r, int j,
                    const Piece& piece, Complex e_theta0, double w);

}  // namespace sliced
}  // namespace drivetrain_stiffness
