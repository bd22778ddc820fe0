// The transmission-error output: each output sample to PipelineSink::transmissionError with what
// its tf frames and markers need (SampleContext: the encoder pinion angle at its stamp, the last
// published resonance). The first SampleConsumer of the dynamics. ROS-free.
#pragma once

#include <optional>

#include "drivetrain_stiffness/pipeline/phase_source.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"
#include "drivetrain_stiffness/pipeline/sample_consumer.hpp"

namespace drivetrain_stiffness {

class TeOutput : public SampleConsumer {
 public:
  /// Keeps references to `phase`, `resonance` (the last published estimate, none since a reset)
  /// and `counters` (te_out).
  TeOutput(const PhaseSource& phase, const std::optional<ResonanceEstimate>& resonance,
           PipelineCounters& counters)
      : phase_(phase), resonance_(resonance), counters_(counters) {}
  /// Counted once the sink took it; a sink's Error passes on (it ends the advance).
  void sample(Stamp stamp, const DynamicsSample& sample, double mesh_frequency,
              PipelineSink& sink) override;
  void restart() override {}

 private:
  const PhaseSource& phase_;
  const std::optional<ResonanceEstimate>& resonance_;
  PipelineCounters& counters_;
};

}  // namespace drivetrain_stiffness
