// stiffness_estimator node: constructs the ROS wrapper and spins. A bad parameter stops the node
// with a message naming it.
#include "drivetrain_stiffness/core/validation.hpp"
#include "drivetrain_stiffness/ros/stiffness_estimator_ros.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "stiffness_estimator");
  try {
    drivetrain_stiffness::StiffnessEstimatorRos node(ros::NodeHandle(), ros::NodeHandle("~"));
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("stiffness_estimator: %s", e.what());
    return 1;
  }
  return 0;
}
