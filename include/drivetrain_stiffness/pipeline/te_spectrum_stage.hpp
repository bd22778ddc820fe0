// The sliding TE spectrum stage: the dynamic TE of the output samples through a SlidingSpectrum;
// every hop its strongest lines go to the sink (te_spectrum). ROS-free; no allocation per sample.
#pragma once

#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"
#include "drivetrain_stiffness/pipeline/sample_consumer.hpp"
#include "drivetrain_stiffness/spectral/sliding_spectrum.hpp"

namespace drivetrain_stiffness {

class TeSpectrumStage : public SampleConsumer {
 public:
  /// `window` [samples] >= 8, `hop` [samples] in [1, window], `interval` [s] > 0 between samples
  /// (InvalidInput otherwise); keeps SpectrumPeaks::kMaxPeaks lines. `counters`: spectra_out.
  TeSpectrumStage(int window, int hop, double interval, PipelineCounters& counters);
  /// Throws InvalidInput for a non-finite TE (SlidingSpectrum::push).
  void sample(Stamp stamp, const DynamicsSample& sample, double mesh_frequency,
              PipelineSink& sink) override;
  /// Empties the window.
  void restart() override { spectrum_.reset(); }
  const SlidingSpectrum& spectrum() const { return spectrum_; }

 private:
  SlidingSpectrum spectrum_;
  SpectrumPeaks peaks_;  ///< the sink's copy (reused)
  PipelineCounters& counters_;
};

}  // namespace drivetrain_stiffness
