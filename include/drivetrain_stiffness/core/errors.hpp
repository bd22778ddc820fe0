// The exceptions the library throws on purpose, under one base: a caller that must not crash on
// bad data (the pipeline, the CLI, the fuzz harness) catches `Error` and nothing wider, so that a
// programming error (std::logic_error, std::out_of_range from a bad index, std::bad_alloc...) is
// not mistaken for bad data: it leaves the library and fails the test or the tool that hit it.
#pragma once

#include <stdexcept>

namespace drivetrain_stiffness {

/// Base of every exception the library throws deliberately. A runtime_error, not a logic_error:
/// each says something about the data (an input, a load, a model), not about the code.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Thrown for any input that is not physically or geometrically admissible.
class InvalidInput : public Error {
 public:
  using Error::Error;
};

/// Thrown when a well-formed input has no admissible solution (e.g. a load the bearing cannot
/// carry).
class UnreachableLoad : public Error {
 public:
  using Error::Error;
};

}  // namespace drivetrain_stiffness
