# Hostile input: fuzz targets over the YAML loaders, the node's parameters, the pipeline's message
# inputs and the replay's bag reader (test/fuzz/, seeds in test/data/fuzz/). Included inside
# if(CATKIN_ENABLE_TESTING). Three drivers share the targets:
#   fuzz_tests       gtest in ctest: every seed, then 1000 seeded mutations per target
#   drivetrain_fuzz  the long run (default 100000 cases per target, per-case watchdog)
#   drivetrain_libfuzzer_<target>  libFuzzer, with -DDRIVETRAIN_LIBFUZZER=ON and clang only

add_library(${PROJECT_NAME}_fuzz_harness STATIC
  test/fuzz/fuzz_targets.cpp
  test/fuzz/case_files.cpp
  test/fuzz/field_rule.cpp
  test/fuzz/refusal.cpp
  test/fuzz/finite_checks.cpp
  test/fuzz/yaml_targets.cpp
  test/fuzz/node_params_target.cpp
  test/fuzz/pipeline_decoder.cpp
  test/fuzz/pipeline_target.cpp
  test/fuzz/bag_target.cpp
  test/fuzz/mutator.cpp
  test/fuzz/fuzz_driver.cpp)
target_include_directories(${PROJECT_NAME}_fuzz_harness PUBLIC test/fuzz)
# _messages: node_parameters.hpp (the node's parameter readers) includes the message sink.
target_link_libraries(${PROJECT_NAME}_fuzz_harness PUBLIC ${PROJECT_NAME}_config ${PROJECT_NAME}_pipeline
  ${PROJECT_NAME}_messages ${PROJECT_NAME}_bag_reader Threads::Threads)
target_compile_definitions(${PROJECT_NAME}_fuzz_harness PRIVATE DRIVETRAIN_SOURCE_DIR="${CMAKE_CURRENT_SOURCE_DIR}")
add_dependencies(${PROJECT_NAME}_fuzz_harness ${PROJECT_NAME}_generate_messages_cpp)

catkin_add_gtest(fuzz_tests test/fuzz/test_fuzz.cpp test/fuzz/test_node_parameters.cpp test/support/test_main.cpp
  WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR})
target_link_libraries(fuzz_tests ${PROJECT_NAME}_fuzz_harness)

add_executable(drivetrain_fuzz test/fuzz/drivetrain_fuzz.cpp)
target_link_libraries(drivetrain_fuzz ${PROJECT_NAME}_fuzz_harness)

# libFuzzer (coverage-guided): needs clang and its runtime (libclang-rt-14-dev), e.g.
#   CXX=clang++ cmake -S . -B build-libfuzzer -DDRIVETRAIN_LIBFUZZER=ON -DDRIVETRAIN_SANITIZE=ON ...
option(DRIVETRAIN_LIBFUZZER "Build the libFuzzer binaries drivetrain_libfuzzer_<target> (clang only)" OFF)
if(DRIVETRAIN_LIBFUZZER)
  include(CheckCXXSourceCompiles)
  set(CMAKE_REQUIRED_LINK_OPTIONS -fsanitize=fuzzer)
  check_cxx_source_compiles("
    #include <cstddef>
    #include <cstdint>
    extern \"C\" int LLVMFuzzerTestOneInput(const std::uint8_t*, std::size_t) { return 0; }"
    DRIVETRAIN_HAVE_LIBFUZZER)
  unset(CMAKE_REQUIRED_LINK_OPTIONS)
  if(NOT DRIVETRAIN_HAVE_LIBFUZZER)
    message(WARNING "DRIVETRAIN_LIBFUZZER: ${CMAKE_CXX_COMPILER_ID} cannot link -fsanitize=fuzzer; use clang++ with libclang-rt-dev")
  else()
    # Coverage instrumentation of the code under test and the harness, so libFuzzer is guided by both.
    foreach(lib core spectral config pipeline bag_reader fuzz_harness)
      target_compile_options(${PROJECT_NAME}_${lib} PRIVATE -fsanitize=fuzzer-no-link)
    endforeach()
    foreach(target bearing_yaml gear_yaml rig_yaml node_params pipeline bag)
      add_executable(drivetrain_libfuzzer_${target} test/fuzz/libfuzzer_main.cpp)
      target_compile_definitions(drivetrain_libfuzzer_${target} PRIVATE DRIVETRAIN_FUZZ_TARGET="${target}")
      target_compile_options(drivetrain_libfuzzer_${target} PRIVATE -fsanitize=fuzzer)
      target_link_libraries(drivetrain_libfuzzer_${target} ${PROJECT_NAME}_fuzz_harness -fsanitize=fuzzer)
    endforeach()
  endif()
endif()
