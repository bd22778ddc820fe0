#include "drivetrain_stiffness/pipeline/phase_source.hpp"

#include <cmath>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {

PhaseSource::PhaseSource(const PipelineOptions& options, int pinion_teeth, int gear_teeth)
    : teeth_p_(pinion_teeth),
      teeth_g_(gear_teeth),
      nominal_speed_(options.pinion_speed_rpm * kTwoPi / 60.0),
      mesh_phase_offset_(options.mesh_phase_offset),
      motion_timeout_(options.motion_timeout),
      gear_ratio_tolerance_(options.gear_ratio_tolerance) {}

double PhaseSource::pinionAngle(Stamp stamp) const {
  if (anchor_) return anchor_->angle + anchor_->speed * secondsBetween(stamp, anchor_->stamp);
  return origin_ ? nominal_speed_ * secondsBetween(stamp, *origin_) : 0.0;
}

double PhaseSource::encoderPinionAngle(Stamp stamp) const {
  // The anchor (a reading, or its time-out continuing it) holds the encoder angle plus the offset
  // that puts the mesh phase where a drive pair enters contact; the nominal angle carries none.
  return anchor_ ? pinionAngle(stamp) - offsetAngle() : pinionAngle(stamp);
}

double PhaseSource::stiffnessAngle(Stamp stamp, Stamp origin) const {
  return anchor_ ? pinionAngle(stamp) : nominal_speed_ * secondsBetween(stamp, origin);
}

double PhaseSource::meshTurns(double pinion_angle) const {
  return pinion_angle * teeth_p_ / kTwoPi;
}

double PhaseSource::meshPhase(double pinion_angle) const {
  const double turns = meshTurns(pinion_angle) + mesh_phase_offset_;
  return turns - std::floor(turns);
}

const char* PhaseSource::name() const {
  if (encoders_) return "encoders";
  return anchor_ ? "nominal (encoders timed out)" : "nominal";
}

std::optional<double> PhaseSource::encoderSilence(Stamp now) const {
  if (!encoders_ || !reading_) return std::nullopt;
  return secondsBetween(now, reading_->stamp);
}

PhaseSource::Reading PhaseSource::unwrap(Stamp stamp, const MotionInput& m,
                                         bool& continuous) const {
  const Reading* last =
      reading_ && secondsBetween(stamp, reading_->stamp) <= motion_timeout_ ? &*reading_ : nullptr;
  continuous = last != nullptr;
  // An angle is used modulo a turn only (exact for any finite double: std::remainder), so an
  // encoder count of any size neither overflows the phase (z_p theta) nor loses the unwrapping.
  // Unwrapped against the prediction from the last reading (an encoder may wrap at +-pi or 2 pi):
  // exact while the shaft turns by less than pi beyond the prediction between two readings.
  const double pinion_in = std::remainder(m.pinion_angle, kTwoPi);
  Reading next;
  next.stamp = stamp;
  const double dt = last ? secondsBetween(stamp, last->stamp) : 0.0;
  next.pinion = pinion_in;
  if (last)
    next.pinion += kTwoPi * std::round((last->pinion + last->speed * dt - pinion_in) / kTwoPi);
  if (m.pinion_velocity) {
    next.speed = *m.pinion_velocity;
  } else if (last && dt > 0.0) {
    next.speed = (next.pinion - last->pinion) / dt;  // backward difference of the encoder angle
  } else {
    next.speed =
        last ? last->speed : 0.0;  // first reading without velocity: standing until the next
  }
  if (m.gear_angle) {
    // Meshing gears: theta_g = -(z_p / z_g) theta_p + const (+ TE / r_b,g, micro-radians).
    const double gear_in = std::remainder(*m.gear_angle, kTwoPi);
    next.gear = gear_in;
    if (last && last->gear) {
      *next.gear +=
          kTwoPi *
          std::round((*last->gear - ratio() * (next.pinion - last->pinion) - gear_in) / kTwoPi);
    }
    next.gear_reference = last && last->gear_reference
                              ? last->gear_reference
                              : std::optional<double>(*next.gear + ratio() * next.pinion);
  }
  const double max_speed =
      1e5 * kTwoPi / 60.0;  // the bound of ~pinion_speed_rpm and of a measured velocity
  if (!(std::abs(next.speed) <= max_speed)) {
    throwInvalid("joint_states: pinion position", m.pinion_angle,
                 "implies " + formatValue(next.speed) +
                     " rad/s since the last reading (beyond +-1e5 rpm): an encoder "
                     "jump, or readings too far apart to unwrap");
  }
  return next;
}

void PhaseSource::checkGearRatio(Reading& reading) {
  if (!reading.gear) return;
  const double residual = *reading.gear + ratio() * reading.pinion;
  const double off = residual - *reading.gear_reference;
  if (std::abs(off) > gear_ratio_tolerance_) {
    ++counters_.gear_ratio_mismatches;
    events_.record(
        "joint_states: the gear angle moved " + formatValue(off) +
        " rad off -(z_p/z_g) x the pinion angle (more than ~gear_ratio_tolerance): a slip, or a "
        "wrong ~pinion_joint/~gear_joint mapping");
    reading.gear_reference = residual;  // one report per slip; a wrong mapping keeps reporting
  }
}

void PhaseSource::anchorTo(const Reading& reading) {
  reading_ = reading;
  anchor_ = Anchor{reading.stamp, reading.pinion + offsetAngle(), reading.speed};
  encoders_ = true;
}

std::optional<Stamp> PhaseSource::encodersTimedOut(Stamp stamp) {
  if (!encoders_ || !reading_ || secondsBetween(stamp, reading_->stamp) <= motion_timeout_)
    return std::nullopt;
  ++counters_.motion_timeouts;
  events_.record("joint_states: none for ~motion_timeout = " + formatValue(motion_timeout_) +
                 " s: the mesh phase runs at ~pinion_speed_rpm from there");
  return Stamp{reading_->stamp.ns + std::llround(motion_timeout_ * 1e9)};
}

void PhaseSource::fallBackToNominal(Stamp at) {
  anchor_ = Anchor{at, pinionAngle(at), nominal_speed_};
  encoders_ = false;
  reading_.reset();  // a stale reading would unwrap the next one wrongly
}

void PhaseSource::reset() {
  origin_.reset();
  anchor_.reset();
  reading_.reset();
  encoders_ = false;
}

}  // namespace drivetrain_stiffness
