// The stiffness estimator as a nodelet: the same StiffnessEstimatorRos as the node, constructed
// with the nodelet's handles, so zero-copy pipelines can run it inside a nodelet manager.
#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "drivetrain_stiffness/ros/stiffness_estimator_ros.hpp"

namespace drivetrain_stiffness {

class StiffnessEstimatorNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      // Multi-threaded handles: the class locks its own state.
      estimator_ =
          std::make_unique<StiffnessEstimatorRos>(getMTNodeHandle(), getMTPrivateNodeHandle());
    } catch (const std::exception& e) {
      NODELET_FATAL("stiffness_estimator: %s", e.what());
      throw;  // the manager reports the failed load
    }
  }
  std::unique_ptr<StiffnessEstimatorRos> estimator_;
};

}  // namespace drivetrain_stiffness

PLUGINLIB_EXPORT_CLASS(drivetrain_stiffness::StiffnessEstimatorNodelet, nodelet::Nodelet)
