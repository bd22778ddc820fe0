// Random numbers that are the same on every platform for a seed: std::mt19937_64 and
// std::seed_seq are specified exactly by the standard, the library's distributions are not
// (libstdc++ and libc++ draw differently), so the uniform and the Gaussian are made here.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

#include "drivetrain_stiffness/core/constants.hpp"

namespace drivetrain_stiffness {

/// One stream per use (its id), so that a change in one count does not move the others.
class SeededStream {
 public:
  SeededStream(std::uint64_t seed, std::uint32_t stream) {
    std::seed_seq seq{static_cast<std::uint32_t>(seed & 0xffffffffu),
                      static_cast<std::uint32_t>(seed >> 32), stream};
    engine_.seed(seq);
  }
  /// Uniform in [0, 1): the top 53 bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
  /// Standard normal (Box-Muller, the cosine branch only).
  double normal() {
    const double u1 = 1.0 - uniform();  // (0, 1]: the logarithm stays finite
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(kTwoPi * u2);
  }

 private:
  std::mt19937_64 engine_;
};

}  // namespace drivetrain_stiffness
