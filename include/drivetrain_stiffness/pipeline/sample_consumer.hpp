// The interface of the stages fed by the dynamics' output samples (docs/pipeline.md "Stages").
#pragma once

#include "drivetrain_stiffness/core/dynamics/dynamics_estimator.hpp"
#include "drivetrain_stiffness/pipeline/input_types.hpp"
#include "drivetrain_stiffness/pipeline/pipeline_outputs.hpp"

namespace drivetrain_stiffness {

class SampleConsumer {
 public:
  virtual ~SampleConsumer() = default;
  /// One output sample at its exact `stamp`; `mesh_frequency` [Hz] over the advance that made it.
  /// May throw Error (it ends the advance); must not allocate.
  virtual void sample(Stamp stamp, const DynamicsSample& sample, double mesh_frequency,
                      PipelineSink& sink) = 0;
  /// The dynamics stopped, restarted or reset: no earlier sample continues.
  virtual void restart() = 0;
};

}  // namespace drivetrain_stiffness
