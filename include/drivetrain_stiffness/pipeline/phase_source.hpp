// The phase source: what drives the mesh phase, the nominal speed or the rig's encoders (the
// encoder rule, docs/ros_api.md "Time and input rules"). It keeps the pinion angle model (an
// anchor extrapolated at its speed), unwraps each reading against the last one, checks the gear
// angle against the tooth ratio, and falls back to the nominal speed when the encoders time out.
// It never touches the dynamics: RigPipeline hands them the anchor. ROS-free.
#pragma once

#include <optional>

#include "drivetrain_stiffness/core/constants.hpp"
#include "drivetrain_stiffness/core/motion.hpp"
#include "drivetrain_stiffness/pipeline/input_types.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_options.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"

namespace drivetrain_stiffness {

class PhaseSource {
 public:
  /// One encoder reading, unwrapped: angles [rad], pinion speed [rad/s] (measured or differentiated);
  /// gear_reference [rad]: gear + (z_p/z_g) pinion when the ratio was last in tolerance.
  struct Reading {
    Stamp stamp;
    double pinion = 0.0, speed = 0.0;
    std::optional<double> gear, gear_reference;
  };
  /// The pinion angle model: angle(t) = angle + speed (t - stamp) [rad, rad/s], offset included.
  struct Anchor {
    Stamp stamp;
    double angle = 0.0, speed = 0.0;
  };

  /// Uses ~pinion_speed_rpm, ~mesh_phase_offset, ~motion_timeout and ~gear_ratio_tolerance of
  /// `options` (validated); z_p, z_g > 0 teeth. `counters`: motion_timeouts, gear_ratio_mismatches
  /// and last_event (kept by reference).
  PhaseSource(const PipelineOptions& options, int pinion_teeth, int gear_teeth, PipelineCounters& counters);

  /// [rad] at `stamp`: the anchor extrapolated, or the nominal angle since origin() (0 before).
  double pinionAngle(Stamp stamp) const;
  /// pinionAngle less the ~mesh_phase_offset an anchor carries: the angle the encoders count.
  double encoderPinionAngle(Stamp stamp) const;
  /// The angle the stiffness estimate of a torque input at `stamp` is taken at [rad]: the anchor's,
  /// or the nominal speed's since `origin`.
  double stiffnessAngle(Stamp stamp, Stamp origin) const;
  /// Mesh turns of a pinion angle [rad]: z_p angle / 2 pi (unwrapped, no offset).
  double meshTurns(double pinion_angle) const;
  /// The mesh phase [0, 1) of a measured pinion angle [rad], ~mesh_phase_offset included.
  double meshPhase(double pinion_angle) const;
  /// "nominal", "encoders" or "nominal (encoders timed out)".
  const char* name() const;
  /// [s] from the last reading to `now` while the encoders drive the phase; nullopt otherwise.
  std::optional<double> encoderSilence(Stamp now) const;
  bool encodersDrive() const { return encoders_; }
  const std::optional<Anchor>& anchor() const { return anchor_; }
  /// Where the nominal angle counts from (the first torque input after a restart); none before.
  std::optional<Stamp> origin() const { return origin_; }
  void setOrigin(Stamp origin) { origin_ = origin; }

  /// `m` at `stamp` unwrapped against the last reading when it is at most ~motion_timeout old
  /// (`continuous` says whether it was). Changes nothing; throws InvalidInput naming the pinion
  /// position when the implied speed is beyond +-1e5 rpm (an encoder jump).
  Reading unwrap(Stamp stamp, const MotionInput& m, bool& continuous) const;
  /// The gear-ratio check: a gear angle off -(z_p/z_g) pinion by more than ~gear_ratio_tolerance
  /// is counted and reported once (the reading is re-referenced to it).
  void checkGearRatio(Reading& reading);
  /// The encoders drive the phase from this reading on.
  void anchorTo(const Reading& reading);
  /// The encoder time-out rule: the moment the encoders timed out, when they drive the phase and
  /// their last reading is older than ~motion_timeout at `stamp` (counted, in last_event).
  std::optional<Stamp> encodersTimedOut(Stamp stamp);
  /// From `at` on the phase runs at the nominal speed from the angle reached.
  void fallBackToNominal(Stamp at);
  /// Back to the nominal phase with no origin (a pipeline reset).
  void reset();

 private:
  double ratio() const { return static_cast<double>(teeth_p_) / teeth_g_; }  ///< z_p / z_g
  double offsetAngle() const { return mesh_phase_offset_ * kTwoPi / teeth_p_; }  ///< [rad]

  int teeth_p_, teeth_g_;
  double nominal_speed_;  ///< [rad/s]
  double mesh_phase_offset_, motion_timeout_, gear_ratio_tolerance_;
  PipelineCounters& counters_;
  std::optional<Stamp> origin_;
  std::optional<Anchor> anchor_;  ///< set by readings (and their time-out); empty: nominal
  bool encoders_ = false;         ///< the anchor comes from a reading (not a time-out)
  std::optional<Reading> reading_;  ///< the last one, for the next one's unwrapping and ratio check
};

}  // namespace drivetrain_stiffness
