// The library's deliberate exceptions (docs/layout.md "errors.hpp").
#pragma once

#include <stdexcept>

namespace drivetrain_stiffness {

/// Base of every exception the library throws about its data; callers catch this, nothing wider.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// An input that is not physically or geometrically admissible.
class InvalidInput : public Error {
 public:
  using Error::Error;
};

/// A well-formed input without an admissible solution (a load the bearing cannot carry).
class UnreachableLoad : public Error {
 public:
  using Error::Error;
};

}  // namespace drivetrain_stiffness
