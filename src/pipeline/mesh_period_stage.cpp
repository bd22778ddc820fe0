#include "drivetrain_stiffness/pipeline/mesh_period_stage.hpp"

#include <algorithm>
#include <cmath>

namespace drivetrain_stiffness {

MeshPeriodStage::MeshPeriodStage(const DynamicsEstimator& dynamics, double pinion_base_radius)
    : dynamics_(dynamics), base_radius_(pinion_base_radius) {}

void MeshPeriodStage::startBlock(Stamp stamp, const DynamicsSample& s, double turns,
                                 double boundary, double mesh_frequency) {
  Accumulator& a = block_;
  a.in_block = true;
  a.boundary = boundary;
  // Whole periods spanning >= ~10 output samples at this speed (one at least).
  const double n = std::ceil(10.0 * dynamics_.outputInterval() * std::abs(mesh_frequency) - 1e-9);
  a.periods = static_cast<std::uint32_t>(std::clamp(n, 1.0, 1e6));
  a.samples = 0;
  a.start = stamp;
  a.start_turns = turns;
  a.start_velocity = s.state[5];
  a.te_ref = s.dynamic_te;
  a.force_ref = s.mesh_force;
  a.te_sum = a.te_sq = a.force_sum = a.force_sq = a.torque_sum = 0.0;
  a.te_min = a.te_max = s.dynamic_te;
  a.force_min = a.force_max = s.mesh_force;
}

void MeshPeriodStage::accumulate(const DynamicsSample& s, double dt) {
  Accumulator& a = block_;
  const double half = 0.5 * dt;
  const double te0 = a.last_te - a.te_ref, te1 = s.dynamic_te - a.te_ref;
  const double f0 = a.last_force - a.force_ref, f1 = s.mesh_force - a.force_ref;
  a.te_sum += half * (te0 + te1);
  a.te_sq += half * (te0 * te0 + te1 * te1);
  a.force_sum += half * (f0 + f1);
  a.force_sq += half * (f0 * f0 + f1 * f1);
  a.torque_sum += half * (a.last_torque + s.torque);
  ++a.samples;
  a.te_min = std::min(a.te_min, s.dynamic_te);
  a.te_max = std::max(a.te_max, s.dynamic_te);
  a.force_min = std::min(a.force_min, s.mesh_force);
  a.force_max = std::max(a.force_max, s.mesh_force);
}

MeshPeriodStatistics MeshPeriodStage::close(Stamp stamp, const DynamicsSample& s, double count,
                                            double turns, bool forward) const {
  const Accumulator& a = block_;
  MeshPeriodStatistics out;
  out.start = a.start;
  out.end = stamp;
  out.duration = secondsBetween(stamp, a.start);
  const double d = out.duration;
  out.periods =
      static_cast<std::uint32_t>(forward ? count - a.boundary : a.boundary - (count + 1.0));
  out.samples = a.samples;
  const double te_dev = a.te_sum / d, force_dev = a.force_sum / d;
  out.te_mean = a.te_ref + te_dev;
  out.te_rms = std::sqrt(std::max(0.0, a.te_sq / d - te_dev * te_dev));
  out.te_peak_to_peak = a.te_max - a.te_min;
  out.torque = a.torque_sum / d;
  // The momentum balance of the relative mesh coordinate (docs/pipeline.md): not the samples' mean.
  const double drive = out.torque / base_radius_;
  const double inertia =
      dynamics_.fidelity() == Fidelity::kQuasiStatic
          ? 0.0
          : dynamics_.rotorModel().equivalentMass() * (s.state[5] - a.start_velocity) / d;
  out.mesh_force_mean = drive - inertia;
  out.mesh_force_rms = std::sqrt(std::max(0.0, a.force_sq / d - force_dev * force_dev));
  out.mesh_force_peak_to_peak = a.force_max - a.force_min;
  out.mesh_frequency = (turns - a.start_turns) / d;
  return out;
}

void MeshPeriodStage::publish(Stamp stamp, const MeshPeriodStatistics& out, PipelineSink& sink) {
  bool finite = true;
  for (double v :
       {out.te_mean, out.te_rms, out.te_peak_to_peak, out.mesh_force_mean, out.mesh_force_rms,
        out.mesh_force_peak_to_peak, out.mesh_frequency, out.torque}) {
    finite = finite && std::isfinite(v);
  }
  if (finite) {  // never NaN on a topic (the sink's conversion would refuse it inside the advance)
    ++counters_.mesh_period_stats_out;
    sink.meshPeriod(stamp, out);
  } else {
    events_.record("mesh_period_stats: a statistic is not finite (not published)");
  }
}

void MeshPeriodStage::sample(Stamp stamp, const DynamicsSample& s, double mesh_frequency,
                             PipelineSink& sink) {
  Accumulator& a = block_;
  // The unwrapped phase is kept as an integer count plus the sample's phase in [0, 1), so that the
  // count is exact on a switch (phase 0): floor(turns) is the count, not a rounding of it.
  if (!a.have_last) {
    a.have_last = true;
    a.last_turns = s.phase;
    if (s.phase == 0.0)
      startBlock(stamp, s, s.phase, 0.0, mesh_frequency);  // a restart on a switch
  } else {
    const double dt = secondsBetween(stamp, a.last_stamp);
    if (!(dt > 0.0)) return;  // the grid only moves forward
    const double last_count = std::floor(a.last_turns);
    const double last_phase = a.last_turns - last_count;
    // Whole periods between the samples: those the speed implies, corrected by the phases.
    const double count = last_count + std::round(mesh_frequency * dt - (s.phase - last_phase));
    const double turns = count + s.phase;
    if (a.in_block) {
      accumulate(s, dt);
      const bool forward = count >= a.boundary + a.periods;
      const bool backward = count < a.boundary - a.periods;
      if (forward || backward) {
        publish(stamp, close(stamp, s, count, turns, forward), sink);
        startBlock(stamp, s, turns, forward ? count : count + 1.0, mesh_frequency);
      }
    } else if (count != last_count) {
      startBlock(stamp, s, turns, count > last_count ? count : count + 1.0, mesh_frequency);
    }
    a.last_turns = turns;
  }
  a.last_stamp = stamp;
  a.last_te = s.dynamic_te;
  a.last_force = s.mesh_force;
  a.last_torque = s.torque;
}

}  // namespace drivetrain_stiffness
