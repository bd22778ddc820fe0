# Load test and latency tool (10 kHz torque). Included inside if(CATKIN_ENABLE_TESTING), after
# find_package(rostest): the tool is built with the tests (testing is on by default). The soak
# (minutes of 10 kHz with deadline and latency bounds) is a benchmark, scripts/soak, not a test:
# its figures depend on how busy the machine is.

# Torque load on the node and what comes back (latency, counts, the node's diagnostics).
add_library(${PROJECT_NAME}_load_generator STATIC src/tools/latency/load_generator.cpp)
target_include_directories(${PROJECT_NAME}_load_generator PUBLIC src/tools include ${catkin_INCLUDE_DIRS})
target_link_libraries(${PROJECT_NAME}_load_generator ${PROJECT_NAME}_pipeline ${catkin_LIBRARIES} nlohmann_json::nlohmann_json)
add_dependencies(${PROJECT_NAME}_load_generator ${PROJECT_NAME}_generate_messages_cpp)

# launch/latency.launch and scripts/soak: p50/p99 input-to-output latency, deadlines, memory as JSON.
add_executable(drivetrain_latency src/tools/latency/drivetrain_latency.cpp)
target_link_libraries(drivetrain_latency ${PROJECT_NAME}_load_generator)
install(TARGETS drivetrain_latency RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})

# Paced 10 kHz torque, then a burst that outruns the node: nothing lost without a count, no NaN,
# memory bounded; verdicts that hold on a busy machine.
add_rostest_gtest(load_accounting_rostest test/ros/load_accounting.test test/ros/test_load_accounting.cpp)
target_link_libraries(load_accounting_rostest ${PROJECT_NAME}_load_generator)
add_dependencies(load_accounting_rostest stiffness_estimator)
