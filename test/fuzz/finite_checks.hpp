// Nothing non-finite leaves the library: every number the pipeline hands a sink (and so every
// field of the node's messages) is checked. A violation throws FuzzFinding naming the field.
#pragma once

#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"

namespace drivetrain_stiffness::fuzz {

void requireAllFinite(const StiffnessEstimate& estimate);
void requireAllFinite(const DynamicsSample& sample);
void requireAllFinite(const ResonanceEstimate& resonance);
void requireAllFinite(const SpectrumPeaks& peaks);
void requireAllFinite(const CalibrationBands& bands);

/// A sink that checks every output and counts them.
class FiniteSink : public PipelineSink {
 public:
  void stiffness(Stamp stamp, const StiffnessEstimate& estimate,
                 const CalibrationBands& bands) override;
  void transmissionError(Stamp stamp, const DynamicsSample& sample,
                         const SampleContext& context) override;
  void spectrum(Stamp stamp, const SpectrumPeaks& spectrum) override;
  void resonance(Stamp stamp, const ResonanceEstimate& estimate,
                 const CalibrationBands& bands) override;
  void measuredTe(Stamp stamp, const MeasuredTeSample& sample) override;
  void calibration(Stamp stamp, const CalibrationEstimate& estimate) override;
  void meshPeriod(Stamp stamp, const MeshPeriodStatistics& stats) override;
  void modalIdentification(Stamp stamp, const ModalReport& report) override;
  std::uint64_t outputs = 0;
};

}  // namespace drivetrain_stiffness::fuzz
