// The transmission-error output, the dynamics' first SampleConsumer.
#pragma once

#include <optional>

#include "drivetrain_stiffness/pipeline/phase_source.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"
#include "drivetrain_stiffness/pipeline/sample_consumer.hpp"

namespace drivetrain_stiffness {

class TeOutput : public SampleConsumer {
 public:
  /// Keeps references to `phase` and `resonance` (the last published).
  TeOutput(const PhaseSource& phase, const std::optional<ResonanceEstimate>& resonance)
      : phase_(phase), resonance_(resonance) {}
  /// To PipelineSink::transmissionError with its SampleContext; a sink's Error passes on.
  void sample(Stamp stamp, const DynamicsSample& sample, double mesh_frequency,
              PipelineSink& sink) override;
  void restart() override {}
  const TeOutputCounters& counters() const { return counters_; }

 private:
  const PhaseSource& phase_;
  const std::optional<ResonanceEstimate>& resonance_;
  TeOutputCounters counters_;
};

}  // namespace drivetrain_stiffness
