// The phase source: the nominal speed or the encoders drive the mesh phase (the encoders rule,
// docs/ros_api.md). It never touches the dynamics.
#pragma once

#include <optional>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/dynamics/motion.hpp"
#include "drivetrain_stiffness/pipeline/input_types.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_options.hpp"
#include "drivetrain_stiffness/pipeline/stage_counters.hpp"

namespace drivetrain_stiffness {

class PhaseSource {
 public:
  /// One reading, unwrapped [rad, rad/s]; gear_reference = gear + (z_p/z_g) pinion [rad].
  struct Reading {
    Stamp stamp;
    double pinion = 0.0, speed = 0.0;
    std::optional<double> gear, gear_reference;
  };
  /// angle(t) = angle + speed (t - stamp) [rad, rad/s], mesh phase offset included.
  struct Anchor {
    Stamp stamp;
    double angle = 0.0, speed = 0.0;
  };

  /// z_p, z_g > 0 teeth.
  PhaseSource(const PipelineOptions& options, int pinion_teeth, int gear_teeth);

  /// [rad]: the anchor extrapolated, or the nominal angle since origin() (0 before).
  double pinionAngle(Stamp stamp) const;
  /// [rad] pinionAngle without the offset an anchor carries: the encoders' angle.
  double encoderPinionAngle(Stamp stamp) const;
  /// [rad] for a torque input's stiffness: the anchor's, or the nominal one since `origin`.
  double stiffnessAngle(Stamp stamp, Stamp origin) const;
  /// z_p angle / 2 pi [turns] (no offset).
  double meshTurns(double pinion_angle) const;
  /// [0, 1) of a measured angle [rad], offset included.
  double meshPhase(double pinion_angle) const;
  /// "nominal", "encoders" or "nominal (encoders timed out)".
  const char* name() const;
  /// [s] since the last reading while the encoders drive the phase.
  std::optional<double> encoderSilence(Stamp now) const;
  bool encodersDrive() const { return encoders_; }
  const std::optional<Anchor>& anchor() const { return anchor_; }
  const PhaseCounters& counters() const { return counters_; }
  /// The last time-out or gear-ratio mismatch, with its reason.
  const EventLog& events() const { return events_; }
  /// Where the nominal angle counts from (the first torque after a restart).
  std::optional<Stamp> origin() const { return origin_; }
  void setOrigin(Stamp origin) { origin_ = origin; }

  /// `m` unwrapped against a last reading at most ~motion_timeout old (`continuous`). Throws
  /// InvalidInput for an implied speed beyond +-1e5 rpm.
  Reading unwrap(Stamp stamp, const MotionInput& m, bool& continuous) const;
  /// Counts a gear angle off the tooth ratio (once) and re-references it.
  void checkGearRatio(Reading& reading);
  /// The encoders drive the phase from this reading on.
  void anchorTo(const Reading& reading);
  /// When the last reading is older than ~motion_timeout at `stamp`: the moment (counted).
  std::optional<Stamp> encodersTimedOut(Stamp stamp);
  /// From `at` on the phase runs at the nominal speed from the angle reached.
  void fallBackToNominal(Stamp at);
  /// Back to the nominal phase with no origin (a pipeline reset).
  void reset();

 private:
  double ratio() const { return static_cast<double>(teeth_p_) / teeth_g_; }      ///< z_p / z_g
  double offsetAngle() const { return mesh_phase_offset_ * kTwoPi / teeth_p_; }  ///< [rad]

  int teeth_p_, teeth_g_;
  double nominal_speed_;  ///< [rad/s]
  double mesh_phase_offset_, motion_timeout_, gear_ratio_tolerance_;
  PhaseCounters counters_;
  EventLog events_;
  std::optional<Stamp> origin_;
  std::optional<Anchor> anchor_;    ///< empty: nominal
  bool encoders_ = false;           ///< the anchor is a reading's
  std::optional<Reading> reading_;  ///< the last one
};

}  // namespace drivetrain_stiffness
