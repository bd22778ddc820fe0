#include "drivetrain_stiffness/pipeline/te_output.hpp"

namespace drivetrain_stiffness {

void TeOutput::sample(Stamp stamp, const DynamicsSample& s, double /*mesh_frequency*/,
                      PipelineSink& sink) {
  SampleContext context;
  context.pinion_angle = phase_.encoderPinionAngle(stamp);
  context.resonance = resonance_ ? &*resonance_ : nullptr;
  sink.transmissionError(stamp, s, context);
  ++counters_.te_out;
}

}  // namespace drivetrain_stiffness
