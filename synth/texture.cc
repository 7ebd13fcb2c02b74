#include "synth/texture.h"

#include <algorithm>
#include <cmath>

namespace doasido::synth {
namespace {

double Fade(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }

Rgb Mix(const Rgb& a, const Rgb& b, double t) { return a + (b - a) * t; }

double Smoothstep(double e0, double e1, double x) {
  const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

Rgb HsvToRgb(double h, double s, double v) {
  const double c = v * s, hp = std::fmod(h, 1.0) * 6;
  const double x = c * (1 - std::abs(std::fmod(hp, 2.0) - 1));
  Rgb r;
  if (hp < 1)
    r = {c, x, 0};
  else if (hp < 2)
    r = {x, c, 0};
  else if (hp < 3)
    r = {0, c, x};
  else if (hp < 4)
    r = {0, x, c};
  else if (hp < 5)
    r = {x, 0, c};
  else
    r = {c, 0, x};
  return r + Rgb::Constant(v - c);
}

}  // namespace

std::uint64_t Hash(std::uint64_t seed, std::int64_t a, std::int64_t b, std::int64_t c) {
  std::uint64_t z = seed ^ (static_cast<std::uint64_t>(a) * 0x9E3779B97F4A7C15ull) ^
                    (static_cast<std::uint64_t>(b) * 0xC2B2AE3D27D4EB4Full) ^
                    (static_cast<std::uint64_t>(c) * 0x165667B19E3779F9ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

double HashUnit(std::uint64_t h) { return (h >> 11) * (1.0 / 9007199254740992.0); }

double ValueNoise(double x, double y, std::uint64_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  const double tx = Fade(x - fx), ty = Fade(y - fy);
  const double v00 = HashUnit(Hash(seed, ix, iy)), v10 = HashUnit(Hash(seed, ix + 1, iy));
  const double v01 = HashUnit(Hash(seed, ix, iy + 1)), v11 = HashUnit(Hash(seed, ix + 1, iy + 1));
  return (v00 + (v10 - v00) * tx) * (1 - ty) + (v01 + (v11 - v01) * tx) * ty;
}

double Fbm(double x, double y, std::uint64_t seed, int octaves) {
  double sum = 0, amp = 0.5, norm = 0;
  for (int o = 0; o < octaves; ++o) {
    sum += amp * ValueNoise(x, y, seed + o * 7919);
    norm += amp;
    x = x * 2.03 + 17.1;
    y = y * 2.03 + 3.7;
    amp *= 0.5;
  }
  return sum / norm;
}

Rgb TableTexture(const TextureStyle& s, double x, double y) {
  // Planks 11 cm wide along x, with staggered ends every 0.6 m.
  constexpr double kPlank = 0.11, kLength = 0.6;
  const double py = y / kPlank;
  const auto plank = static_cast<std::int64_t>(std::floor(py));
  const double offset = HashUnit(Hash(s.seed, plank, 91)) * kLength;
  const double px = (x + offset) / kLength;
  const auto board = static_cast<std::int64_t>(std::floor(px));
  const std::uint64_t hb = Hash(s.seed, plank, board);
  const double tint = 0.8 + 0.4 * HashUnit(hb);
  const double warp = Fbm(x * 6, y * 40, s.seed + 5, 3);
  const double grain = 0.5 + 0.5 * std::sin((y * 260 + warp * 9 + HashUnit(Hash(hb, 1)) * 6));
  Rgb c = Mix(s.table_a * tint, s.table_b, 0.3 * grain);
  c *= 0.75 + 0.5 * Fbm(x * 30, y * 30, s.seed + 11, 3);
  // Pores and knots: isotropic flecks, so corners are not all along the grain.
  const double fleck = Fbm(x * 110, y * 110, s.seed + 13, 2);
  if (fleck > 0.68) c *= 0.62;
  // Dark seams between planks and at board ends.
  const double dv = std::min(py - std::floor(py), std::ceil(py) - py) * kPlank;
  const double du = std::min(px - std::floor(px), std::ceil(px) - px) * kLength;
  const double seam = std::min(Smoothstep(0.0, 0.003, dv), Smoothstep(0.0, 0.003, du));
  return c * (0.35 + 0.65 * seam);
}

Rgb WallTexture(const TextureStyle& s, double x, double z) {
  constexpr double kTile = 0.15;
  const double tx = x / kTile, tz = z / kTile;
  const auto ix = static_cast<std::int64_t>(std::floor(tx));
  const auto iz = static_cast<std::int64_t>(std::floor(tz));
  const std::uint64_t h = Hash(s.seed, ix, iz, 3);
  Rgb c = s.wall_a * (0.9 + 0.2 * HashUnit(h));
  // Some tiles carry a poster: irregular colour blobs (thresholded noise),
  // non-periodic so that feature trackers find unambiguous corners.
  if (HashUnit(Hash(h, 1)) < 0.35) {
    const double fx = tx - ix, fz = tz - iz;
    const double m = 0.08 + 0.12 * HashUnit(Hash(h, 2));
    if (fx > m && fx < 1 - m && fz > m && fz < 1 - m) {
      const double n = Fbm(x * 40, z * 40, Hash(h, 4), 2);
      const double hue = HashUnit(Hash(h, 3));
      c = n < 0.4    ? HsvToRgb(hue, 0.7, 0.85)
          : n < 0.55 ? HsvToRgb(std::fmod(hue + 0.33, 1.0), 0.6, 0.5)
                     : Rgb(0.92, 0.9, 0.85);
    }
  }
  // Speckle: small dark flecks give every tile trackable texture.
  const double fleck = Fbm(x * 120, z * 120, s.seed + 31, 2);
  if (fleck > 0.68) c *= 0.6;
  c *= 0.8 + 0.4 * Fbm(x * 20, z * 20, s.seed + 23, 3);
  const double gx = std::min(tx - ix, ix + 1 - tx) * kTile;
  const double gz = std::min(tz - iz, iz + 1 - tz) * kTile;
  const double grout = std::min(Smoothstep(0.001, 0.004, gx), Smoothstep(0.001, 0.004, gz));
  return Mix(s.wall_b, c, grout);
}

Rgb ObjectTexture(const TextureStyle& s, const Vec3& p) {
  // A checker band pattern in object-local coordinates gives trackable
  // texture that moves rigidly with the object.
  constexpr double kCell = 0.018;
  const auto i = static_cast<std::int64_t>(std::floor(p.x() / kCell)) +
                 static_cast<std::int64_t>(std::floor(p.y() / kCell)) +
                 static_cast<std::int64_t>(std::floor(p.z() / kCell));
  const double n = Fbm(p.x() * 60 + p.z() * 31, p.y() * 60 - p.z() * 17, s.seed + 41, 3);
  const Rgb base = (i & 1) ? s.object : Mix(s.object, s.object_b, 0.7);
  return base * (0.8 + 0.4 * n);
}

Rgb SkinTexture(const TextureStyle& s, const Vec3& p) {
  const double n = Fbm(p.x() * 80 + p.z() * 40, p.y() * 80, s.seed + 97, 2);
  return s.skin * (0.9 + 0.2 * n);
}

TextureStyle RandomStyle(std::uint64_t seed) {
  TextureStyle s;
  s.seed = seed;
  auto u = [&](int k) { return HashUnit(Hash(seed, k, 1234)); };
  s.table_a = HsvToRgb(0.06 + 0.05 * u(1), 0.5 + 0.3 * u(2), 0.45 + 0.3 * u(3));
  s.table_b = s.table_a * (0.5 + 0.2 * u(4));
  s.wall_a = HsvToRgb(u(5), 0.05 + 0.2 * u(6), 0.7 + 0.25 * u(7));
  s.wall_b = s.wall_a * 0.55;
  // Object colours avoid skin hues so a skin detector can separate them.
  const double hue = 0.25 + 0.7 * u(8);
  s.object = HsvToRgb(hue, 0.65 + 0.3 * u(9), 0.55 + 0.35 * u(10));
  s.object_b = HsvToRgb(std::fmod(hue + 0.5, 1.0), 0.4, 0.95);
  // Skin tones: light to dark.
  const double tone = u(11);
  s.skin = Mix(Rgb(0.93, 0.72, 0.60), Rgb(0.45, 0.28, 0.18), tone);
  return s;
}

}  // namespace doasido::synth
