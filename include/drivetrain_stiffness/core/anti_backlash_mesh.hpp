// Composite mesh stiffness of a scissor (anti-backlash) gear, seed 000 eqs 1-2.
//
// The pinion meshes with the fixed half g1 on its drive flank (stiffness k1, the gear shaft's load
// path) and with the loaded half g2 on its back flank (k2); g2 is pushed against the pinion by the
// preloaded spring k_te with preload torque T_p, so the back path is k_c = k_te k2 / (k_te + k2).
// With F_p = T_p / r_b,gear the spring's preload along the line of action, the equilibrium of the
// pinion and of g2 for a relative approach x (derived in docs/gear_model.md section 3) gives
//   drive-flank force F1 = F_p + k1 x,  back-flank force F2 = F_p - k_c x,  F1 - F2 = F_m,
// so both flanks carry load, and k_s = k1 + k_c (seed 000 eq 1), while
//   -F_p (1 + k_c/k1) <= F_m <= F_p (1 + k1/k_c).
// Above the upper bound the back flank (g2) unloads: single-flank mesh k1, with the backlash of
// seed 000 eq 17 on the back side. Below the lower bound (torque reversal beyond the preload) the
// drive flank (g1) unloads and the reversed load runs through the spring: k_s = k_c.
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "drivetrain_stiffness/core/mesh_stiffness.hpp"

namespace drivetrain_stiffness {

struct RigConfig;

struct AntiBacklashSpec {
  /// k_te along the line of action [N/m] (seed 000 Table 1: 1e4 N/mm); 0 = an ordinary gear
  double spring_stiffness = 0.0;
  double preload_torque = 0.0;  ///< T_p about the gear axis [N·m] (seed 000 Table 1: 1000 N·mm)
  double loaded_gear_face_width = 0.0;  ///< face width of g2 [m]; 0 = the pair's face width
};
/// The spec's own checks (InvalidInput naming anti_backlash.<key>), also run by the YAML loader.
void validateAntiBacklash(const AntiBacklashSpec& spec);

enum class FlankContact { kBoth, kDriveOnly, kBackOnly };
const char* toString(FlankContact contact);

struct CompositeMesh {
  double k1 = 0.0;         ///< drive flank (pinion-g1) [N/m]
  double k2 = 0.0;         ///< back flank (pinion-g2) [N/m]
  double k_chain = 0.0;    ///< k_te k2 / (k_te + k2) [N/m]
  double composite = 0.0;  ///< stiffness of the mesh for this flank state [N/m]
  FlankContact contact = FlankContact::kBoth;
  int drive_pairs = 0, back_pairs = 0;
};

class AntiBacklashMesh {
 public:
  /// Builds the drive and back tables (potential-energy etc. per `model`) with `samples` points.
  /// `stiffness_scale` multiplies every tooth pair's stiffness (k1 and k2, not the spring k_te):
  /// the rig's `mesh.stiffness_scale`, 1 for the drawing's gear (docs/calibration.md).
  AntiBacklashMesh(const GearPairSpec& gears, const AntiBacklashSpec& spec,
                   MeshStiffnessModel model, int samples = 256, double stiffness_scale = 1.0);
  /// The same for a rig: its gears, anti_backlash, mesh model, samples and stiffness scale.
  explicit AntiBacklashMesh(const RigConfig& rig);
  double stiffnessScale() const { return scale_; }

  const SpurGearGeometry& geometry() const { return geometry_; }
  const AntiBacklashSpec& spec() const { return spec_; }
  MeshStiffnessModel model() const { return model_; }
  bool verified() const { return verified_; }
  double preloadForce() const { return preload_force_; }  ///< F_p = T_p / r_b,gear [N]
  /// Both flanks modelled (a scissor spring k_c > 0 or a preload F_p > 0): the mesh force is
  /// k_s delta + c delta' where both are loaded, F_p cancelling; else an ordinary gear's one flank
  /// at a time across its backlash.
  bool antiBacklash() const { return spec_.spring_stiffness > 0.0 || preload_force_ > 0.0; }

  /// Flank state for mesh force F_m [N] along the LOA (positive: pinion drives) at given k1, k_c.
  FlankContact flankContact(double mesh_force, double k1, double k_chain) const {
    return flankContact(mesh_force, k1, k_chain, preload_force_);
  }
  /// The same criterion at preload force F_p [N] (the calibration's estimated T_p / r_b,gear).
  static FlankContact flankContact(double mesh_force, double k1, double k_chain,
                                   double preload_force);
  /// Composite stiffness at mesh phase `phase` in [0, 1) under mesh force F_m [N], from the phase
  /// table: segments between the exact switching phases of both flanks, each sampled uniformly, so
  /// the single/double steps stay sharp and the lookup needs no division.
  CompositeMesh at(double phase, double mesh_force) const;
  /// The same from the pair tables directly (reference for the phase table; slower).
  CompositeMesh exactAt(double phase, double mesh_force) const;
  /// Phases in [0, 1) where the number of drive or back pairs in contact changes.
  const std::vector<double>& switchingPhases() const { return breaks_; }
  /// All phases in [0, 1) where the phase table's interpolation has a node (its slope may change),
  /// switching phases included, sorted. Between two of them k1, k2, k_c are linear in phase.
  std::vector<double> tableNodePhases() const;
  /// Period means of k1, k2 and k_c [N/m]: the exact integrals over one mesh period of what at()
  /// returns. at() interpolates linearly between the nodes of each segment, so the trapezoid over a
  /// segment's nodes is its exact integral; the sum over the segments, which tile [0, 1), is the
  /// period mean. Computed once with the table: the resolution is the table's own, and no sampling
  /// of the steps at the switching phases enters (a midpoint rule over N phases misplaces each step
  /// by up to half a sample: 256 and 512 samples gave different means).
  struct PeriodMeans {
    double k1 = 0.0, k2 = 0.0, k_chain = 0.0;
  };
  const PeriodMeans& periodMeans() const { return means_; }
  /// Drive-flank-only table (the ordinary gear pair) and the g2 table.
  const MeshStiffnessTable& driveTable() const { return *drive_; }
  const MeshStiffnessTable& backTable() const { return *back_; }

 private:
  /// Sets the flank state and the composite stiffness of `c` for mesh force F_m.
  void applyFlankState(CompositeMesh& c, double mesh_force) const;

  SpurGearGeometry geometry_;
  AntiBacklashSpec spec_;
  MeshStiffnessModel model_;
  double scale_ = 1.0;
  bool verified_ = true;
  double preload_force_ = 0.0;
  std::unique_ptr<MeshStiffnessTable> drive_, back_;

  struct Segment {
    double start = 0.0, scale = 0.0;  ///< scale = (samples - 1) / width
    int drive_pairs = 0, back_pairs = 0;
    std::vector<std::array<double, 3>> values;  ///< k1, k2, k_chain at uniform phases
  };
  std::vector<double> breaks_;
  std::vector<Segment> segments_;
  PeriodMeans means_;
};

}  // namespace drivetrain_stiffness
