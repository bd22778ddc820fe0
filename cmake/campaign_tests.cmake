# drivetrain_campaign (Python, dask.distributed; docs/campaign.md). Included from CMakeLists.txt
# inside if(CATKIN_ENABLE_TESTING).

# The change detector against the CUSUM's closed form, and the bag list (no bags, no cluster; < 1 s).
add_test(NAME campaign_change_detector
  COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/campaign/test_detector.py)
add_test(NAME campaign_bag_list
  COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/campaign/test_inputs.py)

if(DRIVETRAIN_WITH_ROS)  # drivetrain_rig_sim and drivetrain_replay write and read bags
# End to end on short simulated bags and a local cluster on the loopback (~2-3 min on 2 cores):
# cluster table = serial table, a killed worker, the cache, damaged bags, the alarm, and every
# listening socket of a 2-worker campaign on 127.0.0.1, the cluster's HTTP servers serving no page.
add_test(NAME campaign_end_to_end
  COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/campaign/test_campaign.py)
set_tests_properties(campaign_end_to_end PROPERTIES TIMEOUT 1500
  ENVIRONMENT "DRIVETRAIN_RIG_SIM=${DEVEL_BIN}/drivetrain_rig_sim;DRIVETRAIN_REPLAY=${DEVEL_BIN}/drivetrain_replay;DRIVETRAIN_CLI=${DEVEL_BIN}/drivetrain_cli")
endif()
