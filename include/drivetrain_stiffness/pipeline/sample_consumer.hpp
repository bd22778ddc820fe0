// The one interface of the stages fed by the dynamics' output samples (the TE output, the sliding
// TE spectrum, the mesh-period statistics): DynamicsStage hands each sample to every consumer in
// the order they were added. A new output from the samples is one more consumer. ROS-free.
#pragma once

#include "drivetrain_stiffness/core/dynamics_estimator.hpp"
#include "drivetrain_stiffness/pipeline/input_types.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"

namespace drivetrain_stiffness {

class SampleConsumer {
 public:
  virtual ~SampleConsumer() = default;
  /// One output sample at `stamp` (exact; sample.t = stamp.toSec()). `mesh_frequency` [Hz]: the
  /// dynamics' over the advance that made it. May throw the library's Error (it ends the advance);
  /// must not allocate (allocation_tests).
  virtual void sample(Stamp stamp, const DynamicsSample& sample, double mesh_frequency,
                      PipelineSink& sink) = 0;
  /// The dynamics stopped or restarted (or the pipeline reset): no earlier sample continues into
  /// the next one.
  virtual void restart() = 0;
};

}  // namespace drivetrain_stiffness
