// Tooth-pair and mesh stiffness of a spur gear pair: three models behind one interface, a table
// over the path of contact for fast lookup, and the ISO 6336-1 method B constants.
//
//  - potential_energy (default): each tooth a cantilever on the root circle, bending, shear and
//    axial compression by the energy method (Yang & Lin 1987; Tian 2004), integrated along the
//    tooth centre line with the exact involute half-thickness; the fillet foundation after
//    Sainsot, Velex & Duverger (J. Mech. Des. 126 (2004) 748); Hertz per Yang & Lin,
//    k_h = pi E b / (4 (1 - nu^2)), load independent. 1/k_pair = 1/k_h + sum_gears (1/k_b + 1/k_s +
//    1/k_a + 1/k_f) (bearing of the series assembly: gear.md section 1.2, ROSS, PHM-BGU).
//  - kuang_yang: the tooth stiffness fit quoted by seed 000 eq 3 (Kuang & Yang 1992), combined with
//    Hertz as eq 3 writes. UNVERIFIED: its coefficients and units could not be checked against the
//    primary paper (docs/gear_model.md); results are labelled as such.
//  - iso6336: ISO 6336-1 method B. It gives no time variation; the pair stiffness is the constant
//    c_gamma_alpha b / eps_alpha, so that the mesh stiffness averages to c_gamma_alpha b, with the
//    single/double steps of the contact ratio.
// All stiffnesses in N/m along the line of action, per tooth pair (whole face width).
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/gear_geometry.hpp"

namespace drivetrain_stiffness {

enum class MeshStiffnessModel { kPotentialEnergy, kKuangYang, kIso6336 };
MeshStiffnessModel parseMeshStiffnessModel(const std::string& field, const std::string& text);
const char* toString(MeshStiffnessModel model);

/// Compliances [m/N] of one tooth loaded at an involute point, whole face width.
struct ToothCompliance {
  double bending = 0.0, shear = 0.0, axial = 0.0, fillet = 0.0;
  double total() const { return bending + shear + axial + fillet; }
};

/// Bending, shear and axial compliance of a tooth (base radius r_b, half tooth angle on the base
/// circle alpha2) loaded at the involute point of pressure angle alpha_c, the cantilever clamped at
/// radius x_root along the centre line (the root circle; a constant-thickness segment 2 r_b
/// sin(alpha2) spans x_root..r_b cos(alpha2) when the root is below the base circle, after Chen &
/// Shao 2011). Gauss-Legendre quadrature of the energy-method integrals (docs/gear_model.md section
/// 2).
ToothCompliance toothBeamCompliance(double rb, double alpha2, double x_root, double alpha_c,
                                    double youngs, double poisson, double width);

/// Fillet-foundation compliance (Sainsot, Velex & Duverger 2004, eq. 4 and Table 1 fits).
double filletFoundationCompliance(double rf, double theta_f, double r_int, double u_f,
                                  double load_angle, double youngs, double width);

/// ISO 6336-1 method B (as implemented in python-gearbox iso.py and gfsReboucas/Drivetrain, whose
/// coefficients agree): per unit face width, in N/m^2 (1 N/(mm um) = 1e9 N/m^2).
struct Iso6336Stiffness {
  double single_stiffness_theoretical = 0.0;  ///< c'_th = 1/q'
  double single_stiffness = 0.0;              ///< c' = c'_th C_M C_R C_B cos(beta) E/E_st
  double mesh_stiffness =
      0.0;  ///< c_gamma_alpha = c' (0.75 eps_alpha + 0.25) (x 0.9 if eps_alpha < 1.2)
  double mesh_stiffness_helical = 0.0;     ///< c_gamma_beta = 0.85 c_gamma_alpha
  double transverse_contact_ratio = 0.0;   ///< eps_alpha used
  double c_m = 0.8, c_r = 1.0, c_b = 1.0;  ///< correction factors used
};
Iso6336Stiffness iso6336Stiffness(const GearPairSpec& spec);

/// One tooth pair's stiffness as a function of where it contacts.
class ToothPairStiffness {
 public:
  virtual ~ToothPairStiffness() = default;
  virtual double pairStiffness(const ContactPoint& c) const = 0;  ///< [N/m]
  virtual bool verified() const { return true; }
};

/// Builds one of the three models for the geometry and a face width b [m] (> 0).
std::unique_ptr<ToothPairStiffness> makeToothPairStiffness(MeshStiffnessModel model,
                                                           const SpurGearGeometry& geometry,
                                                           double face_width);

/// Pair stiffness sampled uniformly over the path of contact [s_A, s_E] at start-up (or when a
/// parameter changes), then looked up by LOA position with linear interpolation: mesh stiffness
/// at a mesh phase is the sum over the pairs in contact, so the single/double steps stay sharp.
class MeshStiffnessTable {
 public:
  MeshStiffnessTable(const SpurGearGeometry& geometry, const ToothPairStiffness& model,
                     int samples = 256);
  double pair(double s) const;       ///< one pair at LOA position s [N/m]
  double drive(double phase) const;  ///< drive-flank mesh stiffness at phase [N/m]
  const SpurGearGeometry& geometry() const { return geometry_; }
  int samples() const { return static_cast<int>(values_.size()); }

 private:
  SpurGearGeometry geometry_;
  double s0_, inv_step_;
  std::vector<double> values_;
};

}  // namespace drivetrain_stiffness
