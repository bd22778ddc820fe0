// The sliding TE spectrum stage (te_spectrum); no allocation per sample.
#pragma once

#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"
#include "drivetrain_stiffness/pipeline/sample_consumer.hpp"
#include "drivetrain_stiffness/spectral/sliding_spectrum.hpp"

namespace drivetrain_stiffness {

class TeSpectrumStage : public SampleConsumer {
 public:
  /// `window` >= 8 and `hop` in [1, window] [samples], `interval` > 0 [s]; InvalidInput otherwise.
  TeSpectrumStage(int window, int hop, double interval);
  /// Throws InvalidInput for a non-finite TE.
  void sample(Stamp stamp, const DynamicsSample& sample, double mesh_frequency,
              PipelineSink& sink) override;
  /// Empties the window.
  void restart() override { spectrum_.reset(); }
  const SlidingSpectrum& spectrum() const { return spectrum_; }
  const SpectrumCounters& counters() const { return counters_; }

 private:
  SlidingSpectrum spectrum_;
  SpectrumPeaks peaks_;
  SpectrumCounters counters_;
};

}  // namespace drivetrain_stiffness
