// The only place the fuzz harness hands messages to RigPipeline: when the input API changes, these
// functions are what to adapt.
#pragma once

#include <vector>

#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"

namespace drivetrain_stiffness::fuzz {

inline InputOutcome feedTorque(RigPipeline& pipeline, Stamp stamp, double torque,
                               PipelineSink& sink, const InputOrigin& origin = {},
                               Backlog backlog = Backlog::kNone) {
  return pipeline.torque(stamp, torque, sink, origin, backlog);
}

inline InputOutcome feedMotion(RigPipeline& pipeline, Stamp stamp, const MotionInput& reading,
                               bool missing_pinion, PipelineSink& sink, const InputOrigin& origin) {
  return missing_pinion
             ? pipeline.motionRefused(stamp, "no joint named 'pinion' (~pinion_joint)", origin)
             : pipeline.motion(stamp, reading, sink, origin);
}

inline InputOutcome feedPreload(RigPipeline& pipeline, Stamp stamp,
                                const std::vector<PreloadSetting>& settings, PipelineSink& sink) {
  return pipeline.preload(stamp, settings, sink);
}

inline InputOutcome feedVibration(RigPipeline& pipeline, Stamp stamp,
                                  const VibrationBlockView& block, PipelineSink& sink,
                                  const InputOrigin& origin) {
  return pipeline.vibration(stamp, block, sink, origin);
}

}  // namespace drivetrain_stiffness::fuzz
