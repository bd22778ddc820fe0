# Soak test and latency tool (10 kHz torque). Included inside if(CATKIN_ENABLE_TESTING), after
# find_package(rostest): the tool is built with the tests (testing is on by default).

# Torque load on the node and what comes back (latency, counts, the node's diagnostics).
add_library(${PROJECT_NAME}_load_generator STATIC src/tools/load_generator.cpp)
target_include_directories(${PROJECT_NAME}_load_generator PUBLIC src/tools include ${catkin_INCLUDE_DIRS})
target_link_libraries(${PROJECT_NAME}_load_generator ${catkin_LIBRARIES} nlohmann_json::nlohmann_json)
add_dependencies(${PROJECT_NAME}_load_generator ${PROJECT_NAME}_generate_messages_cpp)

# launch/latency.launch: p50/p99 input-to-output latency as JSON.
add_executable(drivetrain_latency src/tools/drivetrain_latency.cpp)
target_link_libraries(drivetrain_latency ${PROJECT_NAME}_load_generator)
install(TARGETS drivetrain_latency RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})

# Minutes of 10 kHz torque: nothing dropped, no deadline missed, no memory growth.
add_rostest_gtest(soak_rostest test/ros/soak.test test/ros/test_soak.cpp)
target_link_libraries(soak_rostest ${PROJECT_NAME}_load_generator)
add_dependencies(soak_rostest stiffness_estimator)
