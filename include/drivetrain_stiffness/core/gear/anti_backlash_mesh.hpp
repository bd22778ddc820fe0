// Composite mesh stiffness of a scissor (anti-backlash) gear, seed 000 eqs 1-2: docs/gear_model.md
// "3. Anti-backlash composite".
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "drivetrain_stiffness/core/gear/mesh_stiffness.hpp"

namespace drivetrain_stiffness {

struct RigConfig;

struct AntiBacklashSpec {
  double spring_stiffness = 0.0;        ///< k_te [N/m] along the LOA; 0: an ordinary gear
  double preload_torque = 0.0;          ///< T_p [N·m] about the gear axis
  double loaded_gear_face_width = 0.0;  ///< g2's [m]; 0: the pair's
};
/// Throws InvalidInput naming anti_backlash.<key> for a bad value.
void validateAntiBacklash(const AntiBacklashSpec& spec);

enum class FlankContact { kBoth, kDriveOnly, kBackOnly };
const char* toString(FlankContact contact);

struct CompositeMesh {
  double k1 = 0.0;         ///< [N/m] drive flank (pinion-g1)
  double k2 = 0.0;         ///< [N/m] back flank (pinion-g2)
  double k_chain = 0.0;    ///< k_c = k_te k2 / (k_te + k2) [N/m]
  double composite = 0.0;  ///< [N/m] for this flank state (seed 000 eq 1)
  FlankContact contact = FlankContact::kBoth;
  int drive_pairs = 0, back_pairs = 0;
};

class AntiBacklashMesh {
 public:
  /// The drive and back tables with `samples` points; `stiffness_scale` multiplies k1 and k2, not
  /// k_te. Throws InvalidInput naming the field.
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
  /// Both flanks modelled (k_te > 0 or F_p > 0); else an ordinary gear across its backlash.
  bool antiBacklash() const { return spec_.spring_stiffness > 0.0 || preload_force_ > 0.0; }

  /// The flank state under mesh force F_m [N] (> 0: the pinion drives) at k1, k_c [N/m].
  FlankContact flankContact(double mesh_force, double k1, double k_chain) const {
    return flankContact(mesh_force, k1, k_chain, preload_force_);
  }
  /// The same at preload force F_p [N].
  static FlankContact flankContact(double mesh_force, double k1, double k_chain,
                                   double preload_force);
  /// The composite at mesh phase [0, 1) under mesh force F_m [N], from the phase table.
  CompositeMesh at(double phase, double mesh_force) const;
  /// The same from the pair tables directly (slower).
  CompositeMesh exactAt(double phase, double mesh_force) const;
  /// Phases in [0, 1) where the number of drive or back pairs in contact changes.
  const std::vector<double>& switchingPhases() const { return breaks_; }
  /// The phase table's nodes in [0, 1), sorted; k1, k2, k_c are linear between them.
  std::vector<double> tableNodePhases() const;
  /// The exact period means [N/m] of what at() returns (docs/gear_model.md "Phase table").
  struct PeriodMeans {
    double k1 = 0.0, k2 = 0.0, k_chain = 0.0;
  };
  const PeriodMeans& periodMeans() const { return means_; }
  /// The drive-flank (g1) and back-flank (g2) tables.
  const MeshStiffnessTable& driveTable() const { return *drive_; }
  const MeshStiffnessTable& backTable() const { return *back_; }

 private:
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
