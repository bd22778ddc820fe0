// The soak's torque load without ROS, for the pipeline benchmark and the allocation test: 10 kHz
// inputs of the seed rig's 0.1 N*m with a 10 % ripple at 100 Hz, numbered as a publisher would,
// into a sink that reads every output (so nothing is optimised away).
#pragma once

#include <cmath>
#include <cstdint>

#include "drivetrain_stiffness/pipeline/rig_pipeline.hpp"

namespace drivetrain_stiffness {

struct ReadingSink : PipelineSink {
  double sum = 0.0;
  void stiffness(Stamp, const StiffnessEstimate& e, const CalibrationBands&) override {
    sum += e.mesh.current.composite;
  }
  void transmissionError(Stamp, const DynamicsSample& s, const SampleContext&) override {
    sum += s.dynamic_te;
  }
};

class RippleTorqueFeed {
 public:
  static constexpr double kInterval = 1e-4;  ///< [s] between inputs (10 kHz)
  explicit RippleTorqueFeed(RigPipeline& pipeline) : pipeline_(pipeline) {}
  /// The next input, handled as `backlog` says.
  void next(Backlog backlog = Backlog::kNone) {
    const double t = kInterval * static_cast<double>(k_);
    const double torque = 0.1 * (1.0 + 0.1 * std::sin(2.0 * M_PI * 100.0 * t));
    pipeline_.torque(Stamp{kEpoch + 100000 * k_}, torque, sink_,
                     {"/rig", static_cast<std::uint32_t>(k_), "pinion"}, backlog);
    ++k_;
  }
  double checksum() const { return sink_.sum; }

 private:
  static constexpr std::int64_t kEpoch = 1767225600LL * 1000000000LL;  // 2026-01-01
  RigPipeline& pipeline_;
  ReadingSink sink_;
  std::int64_t k_ = 0;
};

}  // namespace drivetrain_stiffness
