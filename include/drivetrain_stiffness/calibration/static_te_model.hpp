// The quasi-static transmission error the rig's encoders see, as a function of the calibrated
// parameters (docs/calibration.md, "What the encoders see"). With the 3-DOF model of seed 000
// section 3 at rest under a mesh force F (docs/model.md), the encoder TE along the line of action,
//   x = r_b,p theta_p + r_b,g theta_g   (joint_states angles; the gear's falls when the pinion's
//   rises)
// is the model's torsional coordinate x = delta - x_p + x_g + e, with
//  - delta the mesh deflection of the scissor gear (anti_backlash_mesh.hpp, docs/model.md):
//      both flanks:  delta = F / (k1 + k_c)       for -F_p (1 + k_c/k1) <= F <= F_p (1 + k1/k_c)
//      drive only:   delta = (F - F_p) / k1        above (the back half g2 has lifted)
//      back only:    delta = (F + F_p) / k_c       below (the reversed load runs through the
//      spring)
//    with k1 = s_m k1', k2 = s_m k2', k_c = k_te k2 / (k_te + k2), F_p = T_p / r_b,gear;
//  - -x_p + x_g the shafts' displacements along the line of action, from each support's exact
//    static solution (the secant u(F_0 + |F|) - u(F_0), not F / k_tangent: bearing.md, last
//    section), weighted by the support's mesh_load_share (the lever rule of a rigid shaft), divided
//    by the shaft's scale and signed with F;
//  - e the manufacturing TE, which does not depend on load and leaves with the baseline.
// The mesh period is integrated exactly between the switching phases (the stiffness jumps there),
// so the mean and the mesh harmonics carry no sampling error from the steps.
#pragma once

#include <array>
#include <limits>
#include <cmath>
#include <complex>
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "drivetrain_stiffness/core/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/bearing_support.hpp"
#include "drivetrain_stiffness/core/rig_config.hpp"

namespace drivetrain_stiffness {

class StiffnessEstimator;

/// The calibrated parameters, in this order.
enum CalibrationIndex {
  kMeshScale = 0,
  kPinionBearingScale,
  kGearBearingScale,
  kPreloadTorque,
  kTeOffset,
  kCalibrationSize
};
using CalibrationVector = Eigen::Matrix<double, kCalibrationSize, 1>;
using CalibrationMatrix = Eigen::Matrix<double, kCalibrationSize, kCalibrationSize>;
/// Field names of the parameters (message fields, CSV columns, YAML keys of the calibration block).
const char* calibrationName(int index);

/// The angle-domain features of one window: the mean TE and the magnitudes of the first mesh
/// harmonics, each the loaded window's minus the baseline's [m].
constexpr int kFeatureHarmonics = 2;
constexpr int kFeatureSize = 1 + kFeatureHarmonics;
using FeatureVector = Eigen::Matrix<double, kFeatureSize, 1>;

class StaticTeModel {
 public:
  /// Tabulates the drawing's tooth stiffness (scale 1) over one mesh period. Throws InvalidInput
  /// for an invalid rig. `rig_mesh`, if given, must be the rig's own mesh table
  /// (AntiBacklashMesh(rig): its gears, anti_backlash, mesh model and samples); when its
  /// mesh.stiffness_scale is 1 it is the drawing's table and is used read only (one table per rig)
  /// instead of a copy built here.
  explicit StaticTeModel(const RigConfig& rig,
                         std::shared_ptr<const AntiBacklashMesh> rig_mesh = nullptr);
  /// The table of the drawing's tooth stiffness this model reads (shared or its own).
  const AntiBacklashMesh& unitMesh() const { return *unit_; }

  /// Each shaft's displacement along the line of action at pinion torque `torque`, from the
  /// supports' exact static solutions at their current settings in `supports`, at scale 1 (divide
  /// by the shaft's scale), signed with the torque: x_g - x_p split as {-x_p, x_g} [m].
  /// Allocation-free after the first call for the same supports.
  void shaftDeflection(double torque, const StiffnessEstimator& supports,
                       std::array<double, 2>& out);

  /// The period mean and the complex mesh harmonics C_k = 2 <x e^{-i 2 pi k phase}> of the encoder
  /// TE at pinion torque `torque` for parameters `p`, without e, with shaft deflections `shafts`
  /// (shaftDeflection at the same torque, scale 1) and without the TE offset.
  void waveform(const CalibrationVector& p, double torque, const std::array<double, 2>& shafts,
                double& mean, std::array<std::complex<double>, kFeatureHarmonics>& harmonics) const;
  /// The mesh deflection delta at grid point j (flank state from F).
  double meshDeflection(const CalibrationVector& p, double mesh_force, int j) const;
  /// Features at `torque` against the baseline at `baseline_torque` (see FeatureVector).
  FeatureVector features(const CalibrationVector& p, double torque,
                         const std::array<double, 2>& shafts, double baseline_torque,
                         const std::array<double, 2>& baseline_shafts) const;
  /// The encoder TE at mesh phase `phase` minus the baseline's, offset included (the per-reading
  /// prediction the measured TE is compared with).
  double at(const CalibrationVector& p, double phase, double torque,
            const std::array<double, 2>& shafts, double baseline_torque,
            const std::array<double, 2>& baseline_shafts) const;
  /// Phase bins of a window's readings (kPhaseBins per mesh period): how often the encoder sampled
  /// each phase. Readings at a fixed rate often hit the same few phases every period (5 kHz on a
  /// 40 Hz mesh: 125 phases), and the mesh stiffness jumps at the switching phases, so the sampled
  /// mean and harmonics differ from the period integrals (up to 3 % on the second harmonic,
  /// measured on load_sweep bags). The model then predicts what those readings see.
  static constexpr int kPhaseBins = 4096;
  /// Per bin: the number of readings and the sum of their phases (the model is evaluated at the
  /// bin's mean phase: exactly the readings' phase when they repeat, as at a fixed rate; a bin is
  /// 1/4096 of a period, so a bin that straddles a switch costs at most its readings' share).
  struct PhaseHistogram {
    std::array<std::uint32_t, kPhaseBins> count{};
    std::array<double, kPhaseBins> phase_sum{};
    void clear() {
      count.fill(0);
      phase_sum.fill(0.0);
    }
    void add(double phase) {
      const int b = phaseBin(phase);
      ++count[static_cast<std::size_t>(b)];
      phase_sum[static_cast<std::size_t>(b)] += phase - std::floor(phase);
    }
  };
  static int phaseBin(double phase) {
    const int b = static_cast<int>((phase - std::floor(phase)) * kPhaseBins);
    return b < 0 ? 0 : (b >= kPhaseBins ? kPhaseBins - 1 : b);
  }
  /// A window's sampled phases prepared for the model: the occupied bins (their mean phase, the
  /// share of the readings, the tooth stiffness there) and the least-squares projection onto a mean
  /// and the fitted mesh harmonics over those phases, as OrderRegression fits the readings (with
  /// gaps at the switching phases the fit is not a plain Fourier sum). Fixed storage.
  static constexpr int kProjectionTerms = 1 + 2 * 4;  ///< mean and OrderRegression::kMeshHarmonics
  struct SampledPhases {
    int size = 0;
    std::array<double, kPhaseBins> weight{}, k1{}, k2{};
    std::array<Eigen::Matrix<double, kProjectionTerms, 1>, kPhaseBins> basis;
    Eigen::LDLT<Eigen::Matrix<double, kProjectionTerms, kProjectionTerms>> gram;
    bool ok = false;
  };
  /// Fills `out` from a window's histogram (`count` readings in it).
  void prepare(const PhaseHistogram& histogram, long count, SampledPhases& out) const;
  /// features() as the window's readings sample and fit the mesh period.
  FeatureVector sampledFeatures(const CalibrationVector& p, double torque,
                                const std::array<double, 2>& shafts, double baseline_torque,
                                const std::array<double, 2>& baseline_shafts,
                                const SampledPhases& sampled) const;

  /// Whether `phase` lies within `guard` (fraction of a period) of a switching phase, where the TE
  /// jumps and a reading's measured phase (encoder counts, mounting error: ~3e-4 of a period at
  /// 20 arcsec on a 20-tooth pinion) may put it on the wrong side of the step.
  bool nearSwitch(double phase, double guard) const;

  /// Period-mean composite mesh stiffness [N/m] for `p` under pinion torque `torque` (flank state
  /// per phase), and the series compliance mean(x(T) - x(0)) / F [m/N].
  double meanMeshStiffness(const CalibrationVector& p, double torque) const;
  /// Signed mesh force F = T / r_b,pinion [N] (seed 000 eq 14).
  double meshForce(double torque) const { return torque / base_radius_[0]; }
  /// Pinion torque at which the back half lifts, F = F_p (1 + k1/k_c) with period-mean k1, k_c
  /// (the knee of TE against torque), for `p` [N·m].
  double kneeTorque(const CalibrationVector& p) const;
  const std::array<double, 2>& baseRadius() const { return base_radius_; }

 private:
  struct GridPoint {
    double weight = 0.0;        ///< share of the period
    double k1 = 0.0, k2 = 0.0;  ///< tooth stiffness at scale 1 [N/m]
    std::array<std::complex<double>, kFeatureHarmonics> basis;  ///< 2 e^{-i 2 pi k phase}
    double phase = 0.0;
  };
  std::vector<GridPoint> grid_;
  std::shared_ptr<const AntiBacklashMesh>
      unit_;                      ///< the drawing's mesh (scale 1): k1', k2' at any phase
  std::vector<double> switches_;  ///< switching phases in [0, 1)
  /// The flank state at tooth stiffness k1', k2' (scale 1) for p and F: k1, k_c, F_p and the
  /// contact by AntiBacklashMesh's criterion.
  struct Flanks {
    double k1 = 0.0, kc = 0.0, fp = 0.0;
    FlankContact contact = FlankContact::kBoth;
  };
  Flanks flanks(const CalibrationVector& p, double force, double k1u, double k2u) const;
  /// The shafts' deflections {-x_p, x_g} at scale 1 divided by each shaft's scale [m].
  static double bearingTerm(const CalibrationVector& p, const std::array<double, 2>& shafts);
  /// delta at tooth stiffness k1', k2' (scale 1) for p and F.
  double deflection(const CalibrationVector& p, double force, double k1u, double k2u) const;
  double spring_ = 0.0;  ///< k_te [N/m]
  std::array<double, 2> base_radius_{};
  /// Scratch solutions for shaftDeflection (one per support): no allocation once sized. unloaded_
  /// holds the solutions at the radial preloads alone for deflection_memo_.revision.
  std::vector<BearingSolution> loaded_, unloaded_;
  /// shaftDeflection's last result, for the supports' revision (StiffnessEstimator::
  /// supportsRevision, never 0) it was solved at; revision 0: nothing valid, unloaded_ included.
  struct DeflectionMemo {
    long revision = 0;
    double torque = 0.0;
    std::array<double, 2> shafts{};
  };
  DeflectionMemo deflection_memo_;
  /// meanMeshStiffness with both flanks loaded at every grid point, per (mesh scale, preload
  /// torque), and the mesh-force range inside which that holds: there the mean does not depend on
  /// the force, and the calibration's bands ask for it at every stiffness message (1 kHz) with a
  /// handful of parameter vectors that change only when the estimate does. A few entries, reused
  /// in turn; not for concurrent use (one Calibrator owns one model).
  /// Per grid point for one (mesh scale, preload torque): k1 and k_c [N/m], and the mesh forces
  /// [N] beyond which it leaves both flanks (AntiBacklashMesh::flankContact's bounds, divided
  /// out): above, the drive flank alone, F_p (1 + k1/k_c); below, the back half alone,
  /// -F_p (1 + k_c/k1). Infinite where the point never changes state on that side.
  struct FlankPoint {
    double k1 = 0.0, kc = 0.0;
    double above = std::numeric_limits<double>::infinity(),
           below = -std::numeric_limits<double>::infinity();
  };
  struct BothFlankMean {
    double scale = std::numeric_limits<double>::quiet_NaN(), preload = 0.0, mean = 0.0,
           force_low = 0.0, force_high = -1.0;
    double fp = 0.0;  ///< F_p [N] at this entry's preload torque
    /// The grid's flank stiffnesses at this entry's parameters: meanMeshStiffness at a force
    /// outside [force_low, force_high] (above or near the knee) reads its flank states from them.
    std::vector<FlankPoint> points;
    /// The last such force's sum and the range of forces around it in which no point changes its
    /// flank state (so the sum is the same bits): [held_low, held_high], empty until then.
    mutable double held_low = 1.0, held_high = -1.0, held_mean = 0.0;
  };
  const BothFlankMean& bothFlankMean(const CalibrationVector& p) const;
  mutable std::array<BothFlankMean, 16> both_flank_means_{};
  mutable std::size_t next_both_flank_mean_ = 0;
};

}  // namespace drivetrain_stiffness
