#include "rig_vibration.hpp"  // NOLINT(build/include_subdir)

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <random>

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/errors.hpp"
#include "drivetrain_stiffness/core/gear/gear_geometry.hpp"
#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/stiffness_estimator.hpp"
#include "drivetrain_stiffness/core/validation.hpp"
#include "scenarios/seeded_stream.hpp"  // NOLINT(build/include_subdir)

namespace drivetrain_stiffness {
namespace {

/// The vibration draws have stream ids of their own (load_sweep uses 1 to 3): they move none of
/// the other random streams.
enum : std::uint32_t { kRoughnessStream = 101, kSensorNoiseStream = 102 };

/// The modified Bessel function I0 by its power series (Abramowitz & Stegun 9.6.12).
double besselI0(double x) {
  double sum = 1.0, term = 1.0;
  for (int k = 1; k < 60; ++k) {
    term *= (0.5 * x / k) * (0.5 * x / k);
    sum += term;
    if (term < 1e-17 * sum) break;
  }
  return sum;
}

using Matrix62 = Eigen::Matrix<double, 6, 2>;

/// The linearised model about one operating point, discretised exactly over one internal step
/// with the inputs u = [w, F_d] held: w = k_s e + c_s e' [N] the mesh's displacement excitation as
/// a force, F_d [N] the drive force.
struct OperatingPoint {
  double torque = 0.0;        ///< [N*m]
  double mesh_force = 0.0;    ///< [N] F_m = T / r_b,p (seed 000 eq 14)
  double k_mean = 0.0;        ///< [N/m] meanMeshStiffness: what `drivetrain_cli modes` uses
  double c_mesh = 0.0;        ///< [N s/m]
  double k_flank_mean = 0.0;  ///< [N/m] period mean of the composite under F_m
  std::shared_ptr<const AntiBacklashMesh> mesh;
  Matrix6 phi;     ///< exp(A h)
  Matrix62 gamma;  ///< int_0^h exp(A s) ds B
  Eigen::Matrix3d stiffness;
  Eigen::Vector3d mass;
};

OperatingPoint makeOperatingPoint(const RigConfig& rig, StiffnessEstimator& estimator,
                                  double torque, double h) {
  OperatingPoint op;
  op.torque = torque;
  estimator.setTorque(torque);  // throws UnreachableLoad beyond what the supports carry
  op.mesh = estimator.sharedMesh();
  const GearRotorParameters p = rigRotorParameters(rig, *op.mesh, estimator.shaftRadialStiffness());
  op.k_mean = meanMeshStiffness(*op.mesh);
  op.c_mesh = p.mesh_damping;
  op.mesh_force = meshForce(rig.gears, 0, torque);
  double sum = 0.0;
  const int samples = 1024;
  for (int i = 0; i < samples; ++i)
    sum += op.mesh->at((i + 0.5) / samples, op.mesh_force).composite;
  op.k_flank_mean = sum / samples;
  // M q'' + C q' + K q = v w + e_3 F_d over q = (x_p, x_g, x), v = (1, -1, 1): the rhs of
  // GearRotorModel with delta = x + x_p - x_g - e (seed 000 eq 14-16), K and C as modalAnalysis.
  op.mass = Eigen::Vector3d(p.pinion_mass, p.gear_mass, p.equivalentMass());
  op.stiffness = meshBearingMatrix(op.k_mean, p.bearing_stiffness);
  const Eigen::Matrix3d damping = meshBearingMatrix(p.mesh_damping, p.bearing_damping);
  const Eigen::Matrix3d inv_m = op.mass.cwiseInverse().asDiagonal();
  Eigen::Matrix<double, 8, 8> aug = Eigen::Matrix<double, 8, 8>::Zero();
  aug.block<3, 3>(0, 3).setIdentity();
  aug.block<3, 3>(3, 0) = -inv_m * op.stiffness;
  aug.block<3, 3>(3, 3) = -inv_m * damping;
  aug.block<3, 1>(3, 6) = inv_m * Eigen::Vector3d(1.0, -1.0, 1.0);
  aug.block<3, 1>(3, 7) = inv_m * Eigen::Vector3d(0.0, 0.0, 1.0);
  // Zero-order hold: exp(h [[A, B], [0, 0]]) = [[Phi, Gamma], [0, I]] (Van Loan 1978).
  const Eigen::Matrix<double, 8, 8> e = (aug * h).exp();
  op.phi = e.block<6, 6>(0, 0);
  op.gamma = e.block<6, 2>(0, 6);
  return op;
}

/// The static deflection under the inputs: K q = v w + e_3 F_d, at rest.
State6 restState(const OperatingPoint& op, double w, double drive) {
  State6 y = State6::Zero();
  y.head<3>() = op.stiffness.ldlt().solve(Eigen::Vector3d(w, -w, w + drive));
  return y;
}

}  // namespace

std::vector<double> antiAliasFilter(int oversample) {
  if (oversample < 2 || oversample > 16)
    throwInvalid("vibration oversample", oversample, "must be in [2, 16]");
  // Kaiser's design formulas (Oppenheim & Schafer, Discrete-Time Signal Processing, eq 7.62-7.63):
  // beta = 0.1102 (A - 8.7) for A > 50 dB, order M = (A - 8) / (2.285 dw).
  const double attenuation = 100.0;                                 // [dB]
  const double pass = 0.35 / oversample, stop = 0.45 / oversample;  // [cycles per internal sample]
  const double cutoff = 0.5 * (pass + stop);
  const double beta = 0.1102 * (attenuation - 8.7);
  int order = static_cast<int>(std::ceil((attenuation - 8.0) / (2.285 * kTwoPi * (stop - pass))));
  if (order % 2 == 1) ++order;  // odd length: an integer group delay of order / 2 samples
  std::vector<double> taps(static_cast<std::size_t>(order + 1));
  double sum = 0.0;
  const double half = 0.5 * order;
  for (int n = 0; n <= order; ++n) {
    const double x = n - half;
    const double sinc = x == 0.0 ? 2.0 * cutoff : std::sin(kTwoPi * cutoff * x) / (kPi * x);
    const double r = x / half;
    taps[n] = sinc * besselI0(beta * std::sqrt(std::max(0.0, 1.0 - r * r))) / besselI0(beta);
    sum += taps[n];
  }
  for (double& t : taps) t /= sum;  // unit gain at DC
  return taps;
}

std::vector<TorqueKnot> scenarioTorque(const std::vector<RigEvent>& events) {
  std::vector<TorqueKnot> knots;
  for (const RigEvent& e : events) {
    if (e.torque && std::isfinite(*e.torque) && e.frame_id == "pinion" && !e.zero_stamp &&
        e.stamp_offset == 0.0 && e.lost_before == 0 && std::abs(*e.torque) < 1e3)
      knots.push_back({e.t, *e.torque});
  }
  return knots;
}

namespace {

void validateVibration(const RigConfig& rig, const std::vector<TorqueKnot>& torque, double duration,
                       const VibrationSpec& spec) {
  if (torque.empty()) throw InvalidInput("torque: no knot for the vibration");
  requirePositive("vibration_rate", spec.rate);
  if (spec.rate > 1e6) throwInvalid("vibration_rate", spec.rate, "must be <= 1e6 Hz");
  if (spec.block < 1 || spec.block > 1000000)
    throwInvalid("vibration_block", spec.block, "must be in [1, 1e6] samples");
  requireNonNegative("vibration_roughness", spec.roughness);
  requireNonNegative("vibration_noise", spec.noise);
  requirePositive("duration", duration);
  if (!rig.dynamics.present)
    throw InvalidInput("dynamics: the vibration needs the gearbox's 'dynamics:' block");
}

/// Each shaft's first support: the channel that measures it.
std::array<std::string, 2> supportChannels(const RigConfig& rig) {
  std::array<std::string, 2> channels;
  for (int shaft = 0; shaft < 2; ++shaft) {
    for (const BearingSupportConfig& b : rig.bearings) {
      if (b.shaft == shaft) {
        channels[shaft] = b.name;
        break;
      }
    }
    if (channels[shaft].empty())
      throw InvalidInput(std::string("bearings: no support on the ") +
                         (shaft == 0 ? "pinion" : "gear") + " shaft (vibration channels)");
  }
  return channels;
}

/// The linearised model's inputs along the scenario: the held torque's operating point and the
/// mesh excitation (docs/vibration.md "Simulated accelerometers").
class MeshExcitation {
 public:
  MeshExcitation(const RigConfig& rig, const std::vector<TorqueKnot>& torque,
                 const SpeedProfile& speed, const VibrationSpec& spec, double h)
      : rig_(rig),
        torque_(torque),
        speed_(speed),
        spec_(spec),
        h_(h),
        estimator_(rig),
        held_(torque.front().torque),
        op_(makeOperatingPoint(rig, estimator_, held_, h)),
        roughness_(spec.seed, kRoughnessStream) {}

  /// The held torque at t [s]; a new operating point when it moves by over 10 %.
  void advance(double t) {
    held_ = torqueAt(t);
    auto far = [&](double from) {
      return !(std::abs(held_ - from) <= 0.1 * std::max(std::abs(from), 1e-3));
    };
    if (far(op_.torque) && far(refused_)) {
      try {
        op_ = makeOperatingPoint(rig_, estimator_, held_, h_);
      } catch (const Error&) {
        refused_ = held_;
      }
    }
  }

  /// The inputs at t [s]: the mesh excitation e(t) = e_TE + e_k + e_r [m] as a force w [N] (the
  /// model's TE, amplitude x sin of the mesh phase; the loaded stiffness fluctuation as a
  /// displacement, -(k_s(phi) - mean) F_m / (k_mean mean) to first order; the random roughness
  /// e_r), and the drive force [N].
  void input(double t, double& w, double& drive) {
    const double teeth = rig_.gears.teeth[0];
    const double te_amplitude = rig_.dynamics.transmission_error_amplitude;
    const double turns = teeth * speed_.angle(t) / kTwoPi;
    const double phase = turns - std::floor(turns);
    const double mesh_hz = teeth * speed_.speed(t) / kTwoPi;
    const double k = op_.mesh->at(phase, op_.mesh_force).composite;
    const double e = te_amplitude * std::sin(kTwoPi * phase) -
                     (k - op_.k_flank_mean) * op_.mesh_force / (op_.k_mean * op_.k_flank_mean) +
                     spec_.roughness * roughness_.normal();
    const double e_rate = te_amplitude * kTwoPi * mesh_hz * std::cos(kTwoPi * phase);
    w = op_.k_mean * e + op_.c_mesh * e_rate;
    drive = meshForce(rig_.gears, 0, held_);
  }

  const OperatingPoint& operatingPoint() const { return op_; }

 private:
  /// The true torque at t: linear between the knots, held outside them.
  double torqueAt(double t) {
    while (knot_ + 1 < torque_.size() && torque_[knot_ + 1].t <= t) ++knot_;
    const TorqueKnot& a = torque_[knot_];
    if (t <= a.t || knot_ + 1 == torque_.size()) return a.torque;
    const TorqueKnot& b = torque_[knot_ + 1];
    return a.torque + (b.torque - a.torque) * (t - a.t) / (b.t - a.t);
  }

  const RigConfig& rig_;
  const std::vector<TorqueKnot>& torque_;
  const SpeedProfile& speed_;
  const VibrationSpec& spec_;
  double h_;
  StiffnessEstimator estimator_;
  std::size_t knot_ = 0;
  double held_;
  OperatingPoint op_;
  double refused_ = NAN;  ///< a torque the supports do not carry: not tried again nearby
  SeededStream roughness_;
};

/// The internal accelerations filtered and decimated to the output: output sample i at i / rate
/// is sum_k taps[k] a[i os + delay - k] (zero phase), a[j] the internal sample at j h.
class Decimator {
 public:
  Decimator(const VibrationSpec& spec, long base)
      : taps_(antiAliasFilter(spec.oversample)),
        delay_(static_cast<long>(taps_.size() / 2)),
        os_(spec.oversample),
        noise_level_(spec.noise),
        base_(base),
        noise_(spec.seed, kSensorNoiseStream) {}
  long delay() const { return delay_; }

  /// Internal sample j's accelerations of the two shafts [m/s^2]; then every output sample whose
  /// filter window is complete, with sensor noise, into `out` (n_out samples in all).
  void push(long j, double a_pinion, double a_gear, long n_out, std::vector<float>& out) {
    ap_.push_back(a_pinion);
    ag_.push_back(a_gear);
    while (next_out_ < n_out && next_out_ * os_ + delay_ <= j) {
      const long last = next_out_ * os_ + delay_ - base_;  // index of taps[0]'s sample
      double sp = 0.0, sg = 0.0;
      for (std::size_t k = 0; k < taps_.size(); ++k) {
        sp += taps_[k] * ap_[static_cast<std::size_t>(last - static_cast<long>(k))];
        sg += taps_[k] * ag_[static_cast<std::size_t>(last - static_cast<long>(k))];
      }
      out[static_cast<std::size_t>(2 * next_out_)] =
          static_cast<float>(sp + noise_level_ * noise_.normal());
      out[static_cast<std::size_t>(2 * next_out_ + 1)] =
          static_cast<float>(sg + noise_level_ * noise_.normal());
      ++next_out_;
    }
    // Drop what no later output needs.
    const long keep_from = next_out_ * os_ - delay_ - base_;
    if (keep_from > 65536) {
      ap_.erase(ap_.begin(), ap_.begin() + keep_from);
      ag_.erase(ag_.begin(), ag_.begin() + keep_from);
      base_ += keep_from;
    }
  }

 private:
  std::vector<double> taps_;
  long delay_;
  int os_;
  double noise_level_;
  long base_;  ///< internal index of ap_[0], ag_[0]
  std::vector<double> ap_, ag_;
  long next_out_ = 0;
  SeededStream noise_;
};

}  // namespace

VibrationRecord simulateVibration(const RigConfig& rig, const std::vector<TorqueKnot>& torque,
                                  const SpeedProfile& speed, double duration,
                                  const VibrationSpec& spec) {
  validateVibration(rig, torque, duration, spec);
  VibrationRecord out;
  out.rate = spec.rate;
  out.block = spec.block;
  out.channels = supportChannels(rig);
  const long blocks = static_cast<long>(std::floor(duration * spec.rate / spec.block + 1e-9));
  const long n_out = blocks * spec.block;
  if (n_out < 1 || n_out > 400000000L)
    throwInvalid("vibration_rate", spec.rate, "gives no whole block or over 4e8 samples");
  out.data.resize(static_cast<std::size_t>(2 * n_out));

  const int os = spec.oversample;
  const double h = 1.0 / (spec.rate * os);
  MeshExcitation excitation(rig, torque, speed, spec, h);
  const long delay = static_cast<long>(antiAliasFilter(os).size() / 2);
  // A lead-in of 0.02 s lets the random response settle.
  const long base = -(static_cast<long>(std::ceil(0.02 / h)) + delay);
  Decimator decimator(spec, base);
  const long j_end = (n_out - 1) * os + delay;
  // Internal step j spans [(j - 1/2) h, (j + 1/2) h] with the inputs at its start held; its sample
  // is the mean acceleration over the step, (v(end) - v(start)) / h, centred on j h. The mean (a
  // box filter, zero at every multiple of the internal rate) keeps the held input's steps from
  // folding the direct term's flat spectrum into the band.
  double w = 0.0, drive = 0.0;
  excitation.advance((base - 0.5) * h);
  excitation.input((base - 0.5) * h, w, drive);
  State6 y = restState(excitation.operatingPoint(), w, drive);
  for (long j = base; j <= j_end; ++j) {
    const double t = (j - 0.5) * h;
    if (j > base) {
      excitation.advance(t);
      excitation.input(t, w, drive);
    }
    const OperatingPoint& op = excitation.operatingPoint();
    const Eigen::Vector2d u(w, drive);
    const State6 next = op.phi * y + op.gamma * u;
    decimator.push(j, (next[3] - y[3]) / h, (next[4] - y[4]) / h, n_out, out.data);
    y = next;
  }
  return out;
}

}  // namespace drivetrain_stiffness
