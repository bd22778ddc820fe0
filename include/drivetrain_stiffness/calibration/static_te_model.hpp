// The quasi-static TE x = delta - x_p + x_g + e the rig's encoders see, as a function of the
// calibrated parameters (3-DOF model of seed 000 section 3 at rest): docs/calibration.md "2. What
// the encoders see"; the caches in "7. Cost".
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

#include "drivetrain_stiffness/core/gear/anti_backlash_mesh.hpp"
#include "drivetrain_stiffness/core/bearing/bearing_support.hpp"
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
/// The parameter's field name (message, CSV, YAML).
const char* calibrationName(int index);

/// A window's features [m]: mean TE, |C_1|, |C_2|, each against the baseline.
constexpr int kFeatureHarmonics = 2;
constexpr int kFeatureSize = 1 + kFeatureHarmonics;
using FeatureVector = Eigen::Matrix<double, kFeatureSize, 1>;

class StaticTeModel {
 public:
  /// The drawing's tooth stiffness over one mesh period; `rig_mesh` (AntiBacklashMesh(rig)) is
  /// shared when its scale is 1. Throws InvalidInput for an invalid rig.
  explicit StaticTeModel(const RigConfig& rig,
                         std::shared_ptr<const AntiBacklashMesh> rig_mesh = nullptr);
  /// The drawing's tooth stiffness table (scale 1).
  const AntiBacklashMesh& unitMesh() const { return *unit_; }

  /// {-x_p, x_g} [m] at pinion torque [N·m]: the supports' secant deflections at scale 1, signed
  /// with the torque. Allocation-free after the first call for the same supports.
  void shaftDeflection(double torque, const StiffnessEstimator& supports,
                       std::array<double, 2>& out);

  /// The period mean [m] and harmonics C_k = 2 <x e^{-i 2 pi k phase}> of x at pinion torque [N·m]
  /// without e and the offset; `shafts` from shaftDeflection at that torque.
  void waveform(const CalibrationVector& p, double torque, const std::array<double, 2>& shafts,
                double& mean, std::array<std::complex<double>, kFeatureHarmonics>& harmonics) const;
  /// delta [m] at grid point j under mesh force [N].
  double meshDeflection(const CalibrationVector& p, double mesh_force, int j) const;
  /// The features at `torque` against the baseline at `baseline_torque` [N·m].
  FeatureVector features(const CalibrationVector& p, double torque,
                         const std::array<double, 2>& shafts, double baseline_torque,
                         const std::array<double, 2>& baseline_shafts) const;
  /// x [m] at mesh phase `phase` minus the baseline's, offset included.
  double at(const CalibrationVector& p, double phase, double torque,
            const std::array<double, 2>& shafts, double baseline_torque,
            const std::array<double, 2>& baseline_shafts) const;
  /// Phase bins per mesh period of a window's readings.
  static constexpr int kPhaseBins = 4096;
  /// Per bin, the readings' count and phase sum.
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
  /// A window's occupied bins and the least-squares projection onto a mean and the mesh harmonics
  /// over them, as OrderRegression fits the readings. Fixed storage.
  static constexpr int kProjectionTerms = 1 + 2 * 4;  ///< mean and OrderRegression::kMeshHarmonics
  struct SampledPhases {
    int size = 0;
    std::array<double, kPhaseBins> weight{}, k1{}, k2{};
    std::array<Eigen::Matrix<double, kProjectionTerms, 1>, kPhaseBins> basis;
    Eigen::LDLT<Eigen::Matrix<double, kProjectionTerms, kProjectionTerms>> gram;
    bool ok = false;
  };
  /// Fills `out` from a window's histogram of `count` readings.
  void prepare(const PhaseHistogram& histogram, long count, SampledPhases& out) const;
  /// features() as the window's readings sample and fit the mesh period.
  FeatureVector sampledFeatures(const CalibrationVector& p, double torque,
                                const std::array<double, 2>& shafts, double baseline_torque,
                                const std::array<double, 2>& baseline_shafts,
                                const SampledPhases& sampled) const;

  /// Whether `phase` lies within `guard` [periods] of a switching phase.
  bool nearSwitch(double phase, double guard) const;

  /// The period-mean composite mesh stiffness [N/m] for `p` under pinion torque [N·m].
  double meanMeshStiffness(const CalibrationVector& p, double torque) const;
  /// Signed mesh force F = T / r_b,pinion [N] (seed 000 eq 14).
  double meshForce(double torque) const { return torque / base_radius_[0]; }
  /// The pinion torque [N·m] where the back half lifts, F = F_p (1 + k1/k_c), period means.
  double kneeTorque(const CalibrationVector& p) const;
  const std::array<double, 2>& baseRadius() const { return base_radius_; }

 private:
  struct GridPoint {
    double weight = 0.0;                                        ///< share of the period
    double k1 = 0.0, k2 = 0.0;                                  ///< [N/m] at scale 1
    std::array<std::complex<double>, kFeatureHarmonics> basis;  ///< 2 e^{-i 2 pi k phase}
    double phase = 0.0;
  };
  std::vector<GridPoint> grid_;
  std::shared_ptr<const AntiBacklashMesh> unit_;  ///< the drawing's mesh (scale 1)
  std::vector<double> switches_;                  ///< switching phases in [0, 1)
  /// k1, k_c, F_p and the contact at tooth stiffness k1', k2' (scale 1) for p and F.
  struct Flanks {
    double k1 = 0.0, kc = 0.0, fp = 0.0;
    FlankContact contact = FlankContact::kBoth;
  };
  Flanks flanks(const CalibrationVector& p, double force, double k1u, double k2u) const;
  /// [m] {-x_p, x_g} at scale 1 divided by each shaft's scale.
  static double bearingTerm(const CalibrationVector& p, const std::array<double, 2>& shafts);
  /// delta at tooth stiffness k1', k2' (scale 1) for p and F.
  double deflection(const CalibrationVector& p, double force, double k1u, double k2u) const;
  double spring_ = 0.0;  ///< k_te [N/m]
  std::array<double, 2> base_radius_{};
  /// shaftDeflection's solutions per support; unloaded_ for deflection_memo_.revision.
  std::vector<BearingSolution> loaded_, unloaded_;
  /// shaftDeflection's last result and the supports' revision it holds for (0: none).
  struct DeflectionMemo {
    long revision = 0;
    double torque = 0.0;
    std::array<double, 2> shafts{};
  };
  DeflectionMemo deflection_memo_;
  /// A grid point's k1, k_c [N/m] and the mesh forces [N] beyond which it leaves both flanks.
  struct FlankPoint {
    double k1 = 0.0, kc = 0.0;
    double above = std::numeric_limits<double>::infinity(),
           below = -std::numeric_limits<double>::infinity();
  };
  struct BothFlankMean {
    double scale = std::numeric_limits<double>::quiet_NaN(), preload = 0.0, mean = 0.0,
           force_low = 0.0, force_high = -1.0;
    double fp = 0.0;  ///< [N]
    std::vector<FlankPoint> points;
    /// The last sum outside [force_low, force_high] and the forces [N] that keep every flank state.
    mutable double held_low = 1.0, held_high = -1.0, held_mean = 0.0;
  };
  const BothFlankMean& bothFlankMean(const CalibrationVector& p) const;
  mutable std::array<BothFlankMean, 16> both_flank_means_{};
  mutable std::size_t next_both_flank_mean_ = 0;
};

}  // namespace drivetrain_stiffness
