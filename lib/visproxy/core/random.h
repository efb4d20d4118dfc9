#pragma once
// Seeded, platform-independent random numbers. Every random choice in visproxy goes
// through this generator so that a seed reproduces a result bit for bit: std::mt19937_64's
// sequence is fixed by the C++ standard, and the conversions below (unlike the standard
// distributions) are the same on every library.

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

#include <Eigen/Core>

namespace visproxy {

class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}

  /// Uniform in [0, 1), 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }

  /// Uniform integer in [0, count); count > 0. Multiply-shift, bias below 2^-64 * count.
  std::uint64_t below(std::uint64_t count) {
    __extension__ using Wide = unsigned __int128;
    return static_cast<std::uint64_t>((static_cast<Wide>(engine_()) * count) >> 64);
  }

  /// Uniformly distributed point on the unit sphere (Archimedes: z is uniform).
  Eigen::Vector3d unit_vector() {
    const double z = 1.0 - 2.0 * uniform();
    const double phi = 2.0 * std::numbers::pi * uniform();
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
  }

 private:
  std::mt19937_64 engine_;
};

}  // namespace visproxy
