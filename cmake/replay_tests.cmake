# Replay, scenario, launch and rviz tests (included from CMakeLists.txt inside CATKIN_ENABLE_TESTING).
set(DEVEL_BIN ${CATKIN_DEVEL_PREFIX}/lib/${PROJECT_NAME})

add_test(NAME replay_bit_identical_and_counts_faults
  COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/test/replay/check_replay.sh ${DEVEL_BIN} ${CMAKE_CURRENT_SOURCE_DIR}
          ${CMAKE_CURRENT_BINARY_DIR}/replay_test)

add_test(NAME replay_follows_the_encoders
  COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/test/replay/check_replay_encoders.sh ${DEVEL_BIN} ${CMAKE_CURRENT_SOURCE_DIR}
          ${CMAKE_CURRENT_BINARY_DIR}/replay_encoders_test)

add_test(NAME run_up_te_follows_the_mesh_order
  COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/test/replay/check_run_up_spectrum.sh ${DEVEL_BIN} ${CMAKE_CURRENT_SOURCE_DIR}
          ${CMAKE_CURRENT_BINARY_DIR}/run_up_spectrum_test)

add_test(NAME rig_sim_reproduces_bundled_bags
  COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/test/replay/check_scenario_bags.sh ${DEVEL_BIN} ${CMAKE_CURRENT_SOURCE_DIR}
          ${CMAKE_CURRENT_BINARY_DIR}/scenario_test)

# drivetrain_rig_sim's encoders: --joint-rate, --no-velocity, --joint-topic, --pinion-joint and
# --gear-joint, read back by Python's rosbag (sensor_msgs/JointState from the bag's definition).
add_test(NAME rig_sim_writes_joint_states
  COMMAND ${CATKIN_DEVEL_PREFIX}/env.sh /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/replay/check_rig_sim_joint_states.py
          ${DEVEL_BIN} ${CMAKE_CURRENT_SOURCE_DIR} ${CMAKE_CURRENT_BINARY_DIR}/joint_states_test)

# drivetrain_rig_sim --scenario load_sweep: reproducible per --seed, its truth in the summary, the
# messages read back by Python's rosbag (a 2 s sweep; load_sweep_tests checks the TE it carries).
add_test(NAME rig_sim_load_sweep
  COMMAND ${CATKIN_DEVEL_PREFIX}/env.sh /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/replay/check_rig_sim_load_sweep.py
          ${DEVEL_BIN} ${CMAKE_CURRENT_SOURCE_DIR} ${CMAKE_CURRENT_BINARY_DIR}/load_sweep_test)

# drivetrain_rig_sim's accelerometers (~15 s): blocks, stamps and channels, drivetrain_replay
# --vibration-topic accepting them, the other topics unchanged, the Welch peaks at the modal
# analysis' frequencies (seed gearbox and pinion bearing scale 0.8), the anti-alias stop band at the
# sensor-noise floor (docs/vibration.md "Simulated accelerometers").
add_test(NAME rig_sim_vibration
  COMMAND ${CATKIN_DEVEL_PREFIX}/env.sh /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/replay/check_rig_sim_vibration.py
          ${DEVEL_BIN} ${CMAKE_CURRENT_SOURCE_DIR} ${CMAKE_CURRENT_BINARY_DIR}/rig_sim_vibration_test)

# The calibration on two load_sweep recordings of drawn rigs (~25 s): errors and identification
# flags against the truth (docs/calibration.md section 6).
add_test(NAME calibration_recovers_drawn_rigs
  COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/replay/check_calibration_mc.py ${DEVEL_BIN} ${CMAKE_CURRENT_SOURCE_DIR})

# The bearing calibration from vibration on rig-sim bags of drawn rigs (scripts/modal_validation,
# docs/vibration.md "Validation"; about 20 s of CPU): 3 rigs (one with a mesh harmonic on a mode)
# and a rig whose two transverse modes lie 2.5 % apart, 20 s each, each replayed against the
# nominal gearbox: the identified frequencies against drivetrain_cli modes of the true gearbox, the
# calibrated bearing scales against the drawn truth, no mesh order reported as a mode; and a 20 s
# run-up whose five 4 s records' modes stay within 0.2 % while the mesh orders cross them.
add_test(NAME modal_validation_recovers_drawn_bearings
  COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/scripts/modal_validation --bin ${DEVEL_BIN}
          --rigs 3 --jobs 2 --check
          --out ${CMAKE_CURRENT_BINARY_DIR}/modal_validation_test)

# The scenario bag writer: joint_states read back by rosbag::View with sensor_msgs/JointState's md5sum.
catkin_add_gtest(scenario_bag_tests test/support/test_main.cpp test/ros/test_scenario_bag.cpp src/tools/rig_sim/scenario_bag.cpp)
target_link_libraries(scenario_bag_tests ${PROJECT_NAME}_scenarios ${PROJECT_NAME}_config ${catkin_LIBRARIES})
target_compile_definitions(scenario_bag_tests PRIVATE DRIVETRAIN_SOURCE_DIR="${CMAKE_CURRENT_SOURCE_DIR}")
add_dependencies(scenario_bag_tests ${PROJECT_NAME}_generate_messages_cpp)

# Damaged bags made at test time from torque_ripple.bag and an LZ4 copy of it: truncated inside the
# first chunk, mid-file, just before the index; an unclosed recording (no index, unfinished chunk);
# garbage over a record and inside an LZ4 chunk; a damaged bag header. Each: exit 4, the error and
# summary.json's status name the file and the byte offset, the outputs are closed and valid, and the
# torque inputs accepted equal the torque messages before the damage (python rosbag on the original).
# Also: a text file is refused with exit 1 naming it; the intact bag gives exit 0 and status "ok".
add_test(NAME replay_damaged_bags_read_up_to_the_damage
  COMMAND ${CATKIN_DEVEL_PREFIX}/env.sh /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/replay/check_damaged_bags.py
          ${DEVEL_BIN} ${CMAKE_CURRENT_SOURCE_DIR} ${CMAKE_CURRENT_BINARY_DIR}/damaged_bags_test)
# Bags another lab would hand the replay, written at test time: a torque in another frame, two kinds
# of refusal, only unrelated topics, a wrong type, one topic for two inputs, a directory or a pipe
# as --bag, gaps with load changes, a frame id that is not UTF-8, encoders that barely turn: the
# exit code, the run summary on stderr, summary.json's inputs and report.md say what happened.
add_test(NAME replay_says_what_it_used_of_a_foreign_bag
  COMMAND ${CATKIN_DEVEL_PREFIX}/env.sh /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/replay/check_foreign_bags.py
          ${DEVEL_BIN} ${CMAKE_CURRENT_SOURCE_DIR} ${CMAKE_CURRENT_BINARY_DIR}/foreign_bags_test)
# --help documents the exit codes, 4 (incomplete) and 5 (no torque accepted) included.
add_test(NAME replay_help_lists_exit_codes COMMAND ${DEVEL_BIN}/drivetrain_replay --help)
set_tests_properties(replay_help_lists_exit_codes PROPERTIES PASS_REGULAR_EXPRESSION "Exit codes.*\n  4  incomplete.*\n  5  no torque accepted")

# The report: summary, markdown and the four plots (matplotlib from Debian's python3).
add_test(NAME replay_report
  COMMAND ${CATKIN_DEVEL_PREFIX}/env.sh ${DEVEL_BIN}/drivetrain_replay --bag ${CMAKE_CURRENT_SOURCE_DIR}/test/data/preload_ramp.bag
          --config ${CMAKE_CURRENT_SOURCE_DIR}/config/gearboxes/seed_servo.yaml --report ${CMAKE_CURRENT_BINARY_DIR}/replay_report)
add_test(NAME replay_report_files
  COMMAND ${CMAKE_COMMAND} -E md5sum ${CMAKE_CURRENT_BINARY_DIR}/replay_report/transmission_error.png
          ${CMAKE_CURRENT_BINARY_DIR}/replay_report/mesh_period_stats.png
          ${CMAKE_CURRENT_BINARY_DIR}/replay_report/stiffness.png ${CMAKE_CURRENT_BINARY_DIR}/replay_report/resonance.png
          ${CMAKE_CURRENT_BINARY_DIR}/replay_report/report.md ${CMAKE_CURRENT_BINARY_DIR}/replay_report/summary.json)
set_tests_properties(replay_report_files PROPERTIES DEPENDS replay_report)

add_test(NAME replay_rejects_missing_bag
  COMMAND ${DEVEL_BIN}/drivetrain_replay --bag ${CMAKE_CURRENT_BINARY_DIR}/no_such.bag
          --config ${CMAKE_CURRENT_SOURCE_DIR}/config/gearboxes/seed_servo.yaml)
set_tests_properties(replay_rejects_missing_bag PROPERTIES PASS_REGULAR_EXPRESSION "--bag = '.*no_such.bag'")
add_test(NAME replay_rejects_bad_params
  COMMAND ${DEVEL_BIN}/drivetrain_replay --bag ${CMAKE_CURRENT_SOURCE_DIR}/test/data/torque_steps.bag
          --config ${CMAKE_CURRENT_SOURCE_DIR}/config/gearboxes/seed_servo.yaml --params ${CMAKE_CURRENT_SOURCE_DIR}/test/data/bad_node_params.yaml)
set_tests_properties(replay_rejects_bad_params PROPERTIES PASS_REGULAR_EXPRESSION "parameter ~output_rate = -1000")

# replay.launch on sim time with a looping bag: outputs stamped in the bag's time, and the clock
# jumping back at each loop resets the estimator, said on /diagnostics.
add_rostest_gtest(replay_launch_rostest test/ros/replay_launch.test test/ros/test_replay_launch.cpp)
target_link_libraries(replay_launch_rostest ${catkin_LIBRARIES})
add_dependencies(replay_launch_rostest stiffness_estimator ${PROJECT_NAME}_generate_messages_cpp)

# The node as a nodelet, its run-time reconfiguration, its start-up validation and its stamp rules.
add_rostest_gtest(graph_robustness_rostest test/ros/graph_robustness.test test/ros/test_graph_robustness.cpp)
target_link_libraries(graph_robustness_rostest ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
add_dependencies(graph_robustness_rostest stiffness_estimator ${PROJECT_NAME}_nodelet)

# rviz with config/drivetrain.rviz under Xvfb, fed by replay.launch; the screenshot must show the markers.
find_program(XVFB_PROGRAM Xvfb)
find_program(RVIZ_PROGRAM rviz)
if(XVFB_PROGRAM AND RVIZ_PROGRAM)
  add_test(NAME rviz_screenshot
    COMMAND ${CATKIN_DEVEL_PREFIX}/env.sh ${CMAKE_CURRENT_SOURCE_DIR}/scripts/rviz_screenshot ${CMAKE_CURRENT_BINARY_DIR}/rviz_screenshot.png)
  set_tests_properties(rviz_screenshot PROPERTIES TIMEOUT 120)  # the exit code says whether the markers showed
else()
  message(WARNING "rviz_screenshot test not registered: needs Xvfb (xvfb) and rviz")
endif()

# The rqt perspective and the README's plot paths name flat numeric message fields.
add_test(NAME plot_paths_are_flat_numeric_fields
  COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/replay/check_plot_fields.py ${CMAKE_CURRENT_SOURCE_DIR})

# The README names every message field, parameter, launch argument and reconfigure setting.
add_test(NAME readme_documents_the_ros_interface
  COMMAND /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/replay/check_readme_coverage.py ${CMAKE_CURRENT_SOURCE_DIR})

# A speed sweep through the resonances: the replayed response peaks at the node's modal estimates.
add_test(NAME speed_sweep_peaks_at_the_estimated_modes
  COMMAND ${CATKIN_DEVEL_PREFIX}/env.sh /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/replay/check_speed_sweep.py
          ${DEVEL_BIN} ${CMAKE_CURRENT_SOURCE_DIR} ${CMAKE_CURRENT_BINARY_DIR}/speed_sweep_test)

# RigVisualizer's display scale: the run-time settings' rule, from the constructor and setExaggeration.
catkin_add_gtest(rig_visualization_tests test/support/test_main.cpp test/ros/test_rig_visualization.cpp)
target_link_libraries(rig_visualization_tests ${PROJECT_NAME}_messages ${PROJECT_NAME}_config)
target_compile_definitions(rig_visualization_tests PRIVATE DRIVETRAIN_SOURCE_DIR="${CMAKE_CURRENT_SOURCE_DIR}")
add_dependencies(rig_visualization_tests ${PROJECT_NAME}_generate_messages_cpp)

# drivetrain_replay's bag writer writes the same bytes as rosbag::Bag, and rosbag::View reads them.
catkin_add_gtest(bag_writer_tests test/ros/test_bag_writer.cpp)
target_include_directories(bag_writer_tests PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/src/tools include)
target_link_libraries(bag_writer_tests ${PROJECT_NAME}_bag_writer ${catkin_LIBRARIES})
add_dependencies(bag_writer_tests ${PROJECT_NAME}_generate_messages_cpp)

# Fault drills: the node killed with SIGKILL and the master restarted under it; roslaunch's respawn
# (rig.launch) brings it back, the restart is counted, and it answers again.
add_test(NAME fault_recovery_sigkill_and_master_restart
  COMMAND ${CATKIN_DEVEL_PREFIX}/env.sh ${CMAKE_CURRENT_SOURCE_DIR}/test/ros/check_fault_recovery.sh
          ${CMAKE_CURRENT_SOURCE_DIR} ${CMAKE_CURRENT_BINARY_DIR}/fault_recovery_test)
set_tests_properties(fault_recovery_sigkill_and_master_restart PROPERTIES TIMEOUT 600)

# The README's quick start from a fresh shell: in an empty environment (env -i), source the devel
# space's setup.bash, then `rosrun drivetrain_stiffness drivetrain_cli --help`, every tool and
# script below resolved by rosrun to the expected file, every launch file by `roslaunch --files`.
# Fails if the sourcing or the lookup by package name breaks - e.g. the devel space back under
# build/, where rosrun finds nothing (scripts/build says why).
# The scripts are the executable ones in scripts/ that users run (motion_analysis.py is a module
# that plot_replay.py imports, not executable, so rosrun does not find it); the optional executables
# are listed when they are built.
set(FRESH_SHELL_TOOLS stiffness_estimator drivetrain_cli drivetrain_replay drivetrain_rig_sim drivetrain_latency
  drivetrain_calibration_mc
  plot_study.py plot_replay.py stiffness_summary.py plot_bench.py summarize_bench.py rviz_screenshot drivetrain_campaign)
foreach(optional drivetrain_bench bearing_benchmark mesh_benchmark motion_benchmark calibration_benchmark
        pipeline_benchmark bag_benchmark)
  if(TARGET ${optional})
    list(APPEND FRESH_SHELL_TOOLS ${optional})
  endif()
endforeach()
add_test(NAME ros_lookup_from_a_fresh_shell
  COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/test/ros/check_fresh_shell.sh ${CATKIN_DEVEL_PREFIX} ${CMAKE_CURRENT_SOURCE_DIR}
          ${FRESH_SHELL_TOOLS})

# drivetrain_replay --calibrate's gearbox YAML: written from an estimate, reloaded with loadRigFile,
# the calibrated values exact and the rest unchanged; bearing files resolve from another directory;
# refusals without a calibration block or without an update.
catkin_add_gtest(replay_calibrate_tests test/support/test_main.cpp test/replay/test_calibrated_gearbox.cpp
  src/tools/replay/calibrated_gearbox.cpp)
target_include_directories(replay_calibrate_tests PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/src/tools)
target_link_libraries(replay_calibrate_tests ${PROJECT_NAME}_config ${PROJECT_NAME}_calibration)
target_compile_definitions(replay_calibrate_tests PRIVATE DRIVETRAIN_SOURCE_DIR="${CMAKE_CURRENT_SOURCE_DIR}")

# The live calibration through drivetrain_replay (the calibration rule): a torque_steps bag with the encoders
# (drivetrain_rig_sim, 5 kHz joint_states) and test/data/calibration_servo.yaml. Twice: bags and CSV
# byte-identical; /calibration and /measured_te in the bag equal calibration.csv and measured_te.csv,
# whose columns are the message fields (msg/*.msg) and whose numbers are finite; --calibrate writes a
# gearbox the replay loads again, or refuses naming why; ~calibrate false and a gearbox without a
# calibration block give no calibration.
add_test(NAME replay_writes_the_calibration
  COMMAND ${CATKIN_DEVEL_PREFIX}/env.sh /usr/bin/python3 ${CMAKE_CURRENT_SOURCE_DIR}/test/replay/check_replay_calibration.py
          ${DEVEL_BIN} ${CMAKE_CURRENT_SOURCE_DIR} ${CMAKE_CURRENT_BINARY_DIR}/replay_calibration_test)

# The node's measured_te and calibration (the calibration rule) on the graph equal the in-process pipeline's for
# the same inputs in the same order, and /diagnostics shows the calibration.
add_rostest_gtest(calibration_topics_rostest test/ros/calibration_topics.test test/ros/test_calibration_topics.cpp)
target_link_libraries(calibration_topics_rostest ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
add_dependencies(calibration_topics_rostest stiffness_estimator ${PROJECT_NAME}_generate_messages_cpp)
add_rostest_gtest(modal_topics_rostest test/ros/modal_topics.test test/ros/test_modal_topics.cpp)
target_include_directories(modal_topics_rostest PRIVATE test/modal)
target_link_libraries(modal_topics_rostest ${PROJECT_NAME}_ros ${catkin_LIBRARIES})
add_dependencies(modal_topics_rostest stiffness_estimator ${PROJECT_NAME}_generate_messages_cpp)
