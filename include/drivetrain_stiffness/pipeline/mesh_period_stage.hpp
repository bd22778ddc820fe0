// The mesh-period statistics stage: docs/pipeline.md "Mesh-period statistics". No allocation per
// sample.
#pragma once

#include <cstdint>

#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"
#include "drivetrain_stiffness/pipeline/sample_consumer.hpp"

namespace drivetrain_stiffness {

class MeshPeriodStage : public SampleConsumer {
 public:
  /// `dynamics`: the model whose samples it receives (kept by reference); `pinion_base_radius`
  /// [m] > 0.
  MeshPeriodStage(const DynamicsEstimator& dynamics, double pinion_base_radius);
  /// Into the running block; a closed, finite block goes to sink.meshPeriod. Samples that do not
  /// move forward in time are skipped.
  void sample(Stamp stamp, const DynamicsSample& sample, double mesh_frequency,
              PipelineSink& sink) override;
  /// Drops the running block; the next block starts at the next mesh-period boundary.
  void restart() override { block_ = Accumulator{}; }
  const MeshPeriodCounters& counters() const { return counters_; }
  /// The last block not published, with its reason.
  const EventLog& events() const { return events_; }

 private:
  struct Accumulator {
    bool have_last = false, in_block = false;
    Stamp last_stamp;
    double last_turns = 0.0;  ///< [turns] unwrapped
    double last_te = 0.0, last_force = 0.0, last_torque = 0.0;
    double boundary = 0.0;  ///< [turns] the block's start
    std::uint32_t periods = 0, samples = 0;
    Stamp start;
    double start_turns = 0.0, start_velocity = 0.0;
    double te_ref = 0.0, force_ref = 0.0;  ///< the start values: the sums are of x - ref
    double te_sum = 0.0, te_sq = 0.0, force_sum = 0.0, force_sq = 0.0,
           torque_sum = 0.0;  ///< trapezoid x dt
    double te_min = 0.0, te_max = 0.0, force_min = 0.0, force_max = 0.0;
  };
  void startBlock(Stamp stamp, const DynamicsSample& s, double turns, double boundary,
                  double mesh_frequency);
  /// The trapezoid from the last sample to `s`, dt [s] long.
  void accumulate(const DynamicsSample& s, double dt);
  /// The block's statistics, ending at `s` at `stamp`, unwrapped phase `turns`.
  MeshPeriodStatistics close(Stamp stamp, const DynamicsSample& s, double count, double turns,
                             bool forward) const;
  void publish(Stamp stamp, const MeshPeriodStatistics& out, PipelineSink& sink);

  const DynamicsEstimator& dynamics_;
  double base_radius_;
  MeshPeriodCounters counters_;
  EventLog events_;
  Accumulator block_;
};

}  // namespace drivetrain_stiffness
