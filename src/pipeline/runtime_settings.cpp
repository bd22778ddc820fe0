#include "drivetrain_stiffness/pipeline/runtime_settings.hpp"

#include "drivetrain_stiffness/core/rig_model.hpp"
#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness {
namespace {

void requireIn(const char* field, double value, double lo, double hi, const char* unit) {
  if (!(value >= lo && value <= hi)) {
    throw InvalidInput(std::string(field) + " = " + formatValue(value) + ": must be in [" +
                       formatValue(lo) + ", " + formatValue(hi) + "]" + unit);
  }
}

}  // namespace

void requireExaggeration(double exaggeration) {
  requireInClosedRange("exaggeration", exaggeration, kMinExaggeration, kMaxExaggeration);
}

void RuntimeSettings::validate() const {
  requireDampingRatio("mesh_damping_ratio", mesh_damping_ratio);
  requireDampingRatio("bearing_damping_ratio", bearing_damping_ratio);
  requireIn("stiffness_rate", stiffness_rate, 0.0, 1e5, " Hz");
  requireExaggeration(exaggeration);
  requireIn("tf_rate", tf_rate, 0.0, 1000.0, " Hz");
}

RuntimeSettings RuntimeSettings::forRig(const RigConfig& rig) {
  RuntimeSettings s;
  if (rig.dynamics.present) {
    s.mesh_damping_ratio = rig.dynamics.mesh_damping_ratio;
    s.bearing_damping_ratio = rig.dynamics.bearing_damping_ratio;
  }
  return s;
}

}  // namespace drivetrain_stiffness
