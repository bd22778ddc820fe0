# -DDRIVETRAIN_SANITIZE=ON: every target compiled and linked with AddressSanitizer and
# UndefinedBehaviorSanitizer (scripts/test --sanitize, in its own build directory). Included near
# the top of CMakeLists.txt, before any target, so that the libraries are instrumented too: a bug
# in the library found only where a test calls it is still a bug in the library.
option(DRIVETRAIN_SANITIZE "Build with -fsanitize=address,undefined" OFF)
if(DRIVETRAIN_SANITIZE)
  # No recovery: a UBSan report fails the test instead of scrolling past in its output.
  set(DRIVETRAIN_SANITIZE_FLAGS -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_compile_options(${DRIVETRAIN_SANITIZE_FLAGS})
  add_link_options(${DRIVETRAIN_SANITIZE_FLAGS})
endif()
