// The annealed sampler's random numbers (internal to retarget/dynamic/):
// one generator shared by the sampler's noise and the planner's
// perturbations, so both draw the same streams on every platform.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace doasido::retarget {

// SplitMix64: a tiny generator whose stream is the same on every platform
// and costs nothing to seed per rollout.
struct Rng {
  std::uint64_t s;
  std::uint64_t Next() {
    std::uint64_t z = (s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  double Uniform() { return (Next() >> 11) * (1.0 / 9007199254740992.0); }
  double Normal() {  // Box-Muller
    const double u = std::max(Uniform(), 1e-300), v = Uniform();
    return std::sqrt(-2 * std::log(u)) * std::cos(2 * M_PI * v);
  }
};

inline std::uint64_t Mix(std::uint64_t a, std::uint64_t b, std::uint64_t c, std::uint64_t d) {
  Rng r{a * 0x100000001b3ULL ^ (b << 40) ^ (c << 20) ^ d};
  return r.Next();
}

}  // namespace doasido::retarget
