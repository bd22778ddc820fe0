// Tooth-pair and mesh stiffness of a spur gear pair [N/m along the line of action, whole face
// width]: three models (docs/gear_model.md "2. Tooth-pair stiffness") and a table over the path of
// contact.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "drivetrain_stiffness/core/gear/gear_geometry.hpp"

namespace drivetrain_stiffness {

/// Potential energy (Yang & Lin 1987; Tian 2004; Sainsot, Velex & Duverger 2004), Kuang & Yang
/// (seed 000 eq 3, unverified), ISO 6336-1 method B.
enum class MeshStiffnessModel { kPotentialEnergy, kKuangYang, kIso6336 };
MeshStiffnessModel parseMeshStiffnessModel(const std::string& field, const std::string& text);
const char* toString(MeshStiffnessModel model);

/// Compliances [m/N] of one tooth loaded at an involute point.
struct ToothCompliance {
  double bending = 0.0, shear = 0.0, axial = 0.0, fillet = 0.0;
  double total() const { return bending + shear + axial + fillet; }
};

/// Bending, shear and axial compliance of a tooth (base radius rb [m], half base angle alpha2
/// [rad]) loaded at pressure angle alpha_c [rad], clamped at x_root [m] (Chen & Shao 2011 below the
/// base circle): the energy-method integrals of docs/gear_model.md section 2.
ToothCompliance toothBeamCompliance(double rb, double alpha2, double x_root, double alpha_c,
                                    double youngs, double poisson, double width);

/// Fillet-foundation compliance [m/N] (Sainsot, Velex & Duverger 2004, eq. 4 and Table 1 fits).
double filletFoundationCompliance(double rf, double theta_f, double r_int, double u_f,
                                  double load_angle, double youngs, double width);

/// ISO 6336-1 method B per unit face width [N/m^2] (docs/gear_model.md "ISO 6336-1 method B").
struct Iso6336Stiffness {
  double single_stiffness_theoretical = 0.0;  ///< c'_th = 1/q'
  double single_stiffness = 0.0;              ///< c' = c'_th C_M C_R C_B cos(beta) E/E_st
  double mesh_stiffness = 0.0;                ///< c_gamma_alpha
  double mesh_stiffness_helical = 0.0;        ///< c_gamma_beta = 0.85 c_gamma_alpha
  double transverse_contact_ratio = 0.0;      ///< eps_alpha
  double c_m = 0.8, c_r = 1.0, c_b = 1.0;     ///< correction factors
};
Iso6336Stiffness iso6336Stiffness(const GearPairSpec& spec);

/// One tooth pair's stiffness by contact point.
class ToothPairStiffness {
 public:
  virtual ~ToothPairStiffness() = default;
  virtual double pairStiffness(const ContactPoint& c) const = 0;  ///< [N/m]
  virtual bool verified() const { return true; }
};

/// One of the models for the geometry and face width b > 0 [m]; InvalidInput otherwise.
std::unique_ptr<ToothPairStiffness> makeToothPairStiffness(MeshStiffnessModel model,
                                                           const SpurGearGeometry& geometry,
                                                           double face_width);

/// Pair stiffness sampled over the path of contact, interpolated linearly; the mesh stiffness is
/// the sum over the pairs in contact.
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
