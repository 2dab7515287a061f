#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>

// Procedural textures of the synthetic scene: deterministic functions of a surface point
// (texture coordinates in metres) and a seed. Every pattern takes the pixel footprint (size
// in metres of one pixel on the surface) and fades out detail finer than about two
// footprints, which both anti-aliases and skips work on distant surfaces.
namespace parallax {

// A 32-bit integer hash with good avalanche (a "lowbias32" mixer).
inline uint32_t Mix32(uint32_t h) {
  h ^= h >> 16;
  h *= 0x7FEB352Du;
  h ^= h >> 15;
  h *= 0x846CA68Bu;
  h ^= h >> 16;
  return h;
}

inline uint32_t HashCell(int32_t x, int32_t y, uint32_t seed) {
  return Mix32(static_cast<uint32_t>(x) * 0x8DA6B343u +
               Mix32(static_cast<uint32_t>(y) * 0xD8163841u + seed));
}

// A hash mapped to [0, 1).
inline float UnitFloat(uint32_t h) { return static_cast<float>(h >> 8) * (1.0f / 16777216.0f); }

inline float SmoothStep(float edge0, float edge1, float x) {
  const float t = std::clamp((x - edge0) / (edge1 - edge0), 0.0f, 1.0f);
  return t * t * (3.0f - 2.0f * t);
}

// Weight of a pattern of this wavelength: 1 when it spans 4 footprints or more, 0 at 2 or
// fewer (where it would alias).
inline float LodWeight(float wavelength, float footprint) {
  return std::clamp(0.5f * wavelength / footprint - 1.0f, 0.0f, 1.0f);
}

// Value noise on the unit lattice, smoothly interpolated, in [0, 1].
inline float ValueNoise(float x, float y, uint32_t seed) {
  const float fx = std::floor(x), fy = std::floor(y);
  const int32_t ix = static_cast<int32_t>(fx), iy = static_cast<int32_t>(fy);
  float tx = x - fx, ty = y - fy;
  tx = tx * tx * (3.0f - 2.0f * tx);
  ty = ty * ty * (3.0f - 2.0f * ty);
  const float a = UnitFloat(HashCell(ix, iy, seed)), b = UnitFloat(HashCell(ix + 1, iy, seed));
  const float c = UnitFloat(HashCell(ix, iy + 1, seed)),
              d = UnitFloat(HashCell(ix + 1, iy + 1, seed));
  const float top = a + (b - a) * tx, bottom = c + (d - c) * tx;
  return top + (bottom - top) * ty;
}

// Fractal sum of value noise from `wavelength` (metres) down over `octaves` halvings, each
// octave rotated so that the lattice does not show. Mean 0.5; octaves below the footprint
// contribute their mean, so contrast fades as a blur would.
float Fbm(const Eigen::Vector2f& p, uint32_t seed, float wavelength, int octaves, float footprint,
          float gain = 0.6f);

// Round dots, at most one per cell of a square grid (`cell` metres), present with
// probability `density`. Returns the dot's coverage of the point in [0, 1] (edges
// anti-aliased over the footprint) and its random value in [0, 1) in `value`.
float Dots(const Eigen::Vector2f& p, float cell, float density, uint32_t seed, float footprint,
           float* value);

// Blocks in running bond (every other row shifted by half a block): the block's hash in
// `block_id` and the coverage of the mortar joints (width `mortar`) at the point.
float Blocks(const Eigen::Vector2f& p, float width, float height, float mortar, uint32_t seed,
             float footprint, uint32_t* block_id);

// Albedos (RGB in [0, 1]) of the materials of the temple scene.
Eigen::Vector3f EarthAlbedo(const Eigen::Vector2f& p, uint32_t seed, float footprint);
Eigen::Vector3f PavingAlbedo(const Eigen::Vector2f& p, uint32_t seed, float footprint);
Eigen::Vector3f MarbleAlbedo(const Eigen::Vector2f& p, uint32_t seed, float footprint);
// p = (arc length around the column, height).
Eigen::Vector3f ColumnAlbedo(const Eigen::Vector2f& p, uint32_t seed, float footprint,
                             float radius);
Eigen::Vector3f AshlarAlbedo(const Eigen::Vector2f& p, uint32_t seed, float footprint);
Eigen::Vector3f RoofTileAlbedo(const Eigen::Vector2f& p, uint32_t seed, float footprint);
// Albedos of the town seen from the air. Asphalt textured at `p`, with a dashed centre line
// where `across` (metres from the street's axis) is 0, dashes by `along`.
Eigen::Vector3f AsphaltAlbedo(const Eigen::Vector2f& p, float along, float across, uint32_t seed,
                              float footprint);
// A ploughed or planted field: rows along u, their spacing and colour from `crop_seed`, the
// soil's detail from `seed`.
Eigen::Vector3f FieldAlbedo(const Eigen::Vector2f& p, uint32_t crop_seed, uint32_t seed,
                            float footprint);

}  // namespace parallax
