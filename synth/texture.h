// Procedural textures for the synthetic world. They have structure at several
// scales (plank seams, tile grout, posters, grain, fine noise) so that optical
// flow, Shi-Tomasi corners and colour histograms behave as on real footage.
// Every texture is a pure function of its seed and the surface coordinates
// (metres), so frames are reproducible.
#pragma once

#include <cstdint>

#include "core/geometry.h"

namespace doasido::synth {

// Colours are linear RGB in [0, 1].
using Rgb = Eigen::Vector3d;

// Smooth value noise in [0, 1] (bilinear-quintic lattice noise).
double ValueNoise(double x, double y, std::uint64_t seed);
// Fractal sum of `octaves` ValueNoise layers, in [0, 1].
double Fbm(double x, double y, std::uint64_t seed, int octaves = 4);
// A 64-bit hash of integers and a seed (SplitMix64 finaliser).
std::uint64_t Hash(std::uint64_t seed, std::int64_t a, std::int64_t b = 0, std::int64_t c = 0);
// Uniform [0, 1) from a hash.
double HashUnit(std::uint64_t h);

struct TextureStyle {
  std::uint64_t seed = 1;
  Rgb table_a{0.55, 0.36, 0.20};   // wood base
  Rgb table_b{0.35, 0.22, 0.12};   // grain and seams
  Rgb wall_a{0.80, 0.78, 0.72};    // tiles
  Rgb wall_b{0.45, 0.45, 0.48};    // grout
  Rgb object{0.75, 0.15, 0.12};    // object base colour
  Rgb object_b{0.95, 0.90, 0.30};  // object pattern colour
  Rgb skin{0.85, 0.60, 0.46};
};

// A table (wood planks) at table-plane coordinates (x, y).
Rgb TableTexture(const TextureStyle& style, double x, double y);
// The back wall (tiles with posters) at wall coordinates (x, z).
Rgb WallTexture(const TextureStyle& style, double x, double z);
// The object's surface at object-local coordinates.
Rgb ObjectTexture(const TextureStyle& style, const Vec3& p);
// Skin at hand-local position p (mild blotches).
Rgb SkinTexture(const TextureStyle& style, const Vec3& p);

// A random style (colours, seeds) from `seed`.
TextureStyle RandomStyle(std::uint64_t seed);

}  // namespace doasido::synth
