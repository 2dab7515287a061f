#include "parallax/render/procedural_texture.h"

#include <numbers>

namespace parallax {
namespace {

inline Eigen::Vector3f Mix(const Eigen::Vector3f& a, const Eigen::Vector3f& b, float t) {
  return a + (b - a) * t;
}

// Brightness factor of a fractal detail layer around 1 (contrast: gain per unit deviation).
inline float Detail(const Eigen::Vector2f& p, uint32_t seed, float wavelength, int octaves,
                    float footprint, float contrast) {
  return 1.0f + contrast * (Fbm(p, seed, wavelength, octaves, footprint, 0.65f) - 0.5f);
}

// Two layers of speckles (pebbles, lichen, pits) blended over a colour.
inline Eigen::Vector3f Speckle(const Eigen::Vector2f& p, uint32_t seed, float footprint, float cell,
                               const Eigen::Vector3f& color, const Eigen::Vector3f& dark,
                               const Eigen::Vector3f& light) {
  Eigen::Vector3f result = color;
  float value;
  float coverage = Dots(p, cell, 0.55f, seed ^ 0xA511E9B3u, footprint, &value);
  if (coverage > 0) result = Mix(result, Mix(dark, light, value), coverage);
  coverage = Dots(p, 0.37f * cell, 0.45f, seed ^ 0x63D83595u, footprint, &value);
  if (coverage > 0) result = Mix(result, Mix(dark, light, value), 0.8f * coverage);
  return result;
}

}  // namespace

float Fbm(const Eigen::Vector2f& p, uint32_t seed, float wavelength, int octaves, float footprint,
          float gain) {
  // Rotation by about 36.87 degrees (3-4-5 triangle) between octaves.
  constexpr float kCos = 0.8f, kSin = 0.6f;
  float x = p.x() / wavelength, y = p.y() / wavelength;
  float sum = 0.0f, amplitude = 1.0f, total = 0.0f;
  for (int octave = 0; octave < octaves; ++octave) {
    total += amplitude;
    const float weight = LodWeight(wavelength, footprint);
    if (weight > 0.0f) {
      sum += amplitude * weight * (ValueNoise(x, y, seed + 0x68E31DA4u * octave) - 0.5f);
    }
    amplitude *= gain;
    wavelength *= 0.5f;
    const float rotated_x = 2.0f * (kCos * x - kSin * y);
    y = 2.0f * (kSin * x + kCos * y);
    x = rotated_x;
  }
  return 0.5f + sum / total;
}

float Dots(const Eigen::Vector2f& p, float cell, float density, uint32_t seed, float footprint,
           float* value) {
  // Dots are a third to three quarters of a cell across.
  const float lod = LodWeight(0.6f * cell, footprint);
  if (lod <= 0.0f) return 0.0f;
  const float qx = p.x() / cell, qy = p.y() / cell;
  const float fx = std::floor(qx), fy = std::floor(qy);
  const uint32_t h = HashCell(static_cast<int32_t>(fx), static_cast<int32_t>(fy), seed);
  if (UnitFloat(h) >= density) return 0.0f;
  const uint32_t h2 = Mix32(h ^ 0x5BD1E995u);
  const float radius = 0.17f + 0.2f * UnitFloat(h2);
  const float cx = fx + 0.5f + (0.5f - radius) * (2.0f * UnitFloat(Mix32(h2 + 1)) - 1.0f);
  const float cy = fy + 0.5f + (0.5f - radius) * (2.0f * UnitFloat(Mix32(h2 + 2)) - 1.0f);
  const float distance = std::sqrt((qx - cx) * (qx - cx) + (qy - cy) * (qy - cy));
  const float edge = std::max(footprint / cell, 1e-4f);
  *value = UnitFloat(Mix32(h2 + 3));
  return lod * std::clamp((radius - distance) / edge + 0.5f, 0.0f, 1.0f);
}

float Blocks(const Eigen::Vector2f& p, float width, float height, float mortar, uint32_t seed,
             float footprint, uint32_t* block_id) {
  const float row = std::floor(p.y() / height);
  const int32_t row_idx = static_cast<int32_t>(row);
  const float shifted = p.x() / width + ((row_idx & 1) ? 0.5f : 0.0f);
  const float col = std::floor(shifted);
  *block_id = HashCell(static_cast<int32_t>(col), row_idx, seed);
  const float local_x = (shifted - col) * width, local_y = (p.y() / height - row) * height;
  const float distance =
      std::min(std::min(local_x, width - local_x), std::min(local_y, height - local_y));
  // A box filter of the joint over one footprint.
  const float coverage =
      std::clamp((0.5f * mortar - distance) / std::max(footprint, 1e-5f) + 0.5f, 0.0f, 1.0f);
  // Blocks only a few pixels across fade to the mean joint coverage.
  const float mean = mortar * (width + height) / (width * height);
  const float lod = LodWeight(std::min(width, height), footprint);
  return mean + (coverage - mean) * lod;
}

Eigen::Vector3f EarthAlbedo(const Eigen::Vector2f& p, uint32_t seed, float footprint) {
  const float patches = Fbm(p, seed, 14.0f, 3, footprint);
  const Eigen::Vector3f earth(0.56f, 0.47f, 0.35f), grass(0.34f, 0.45f, 0.22f);
  Eigen::Vector3f color = Mix(earth, grass, SmoothStep(0.42f, 0.58f, patches));
  color *= Detail(p, seed + 1, 2.5f, 9, footprint, 2.2f);
  return Speckle(p, seed + 2, footprint, 0.45f, color, Eigen::Vector3f(0.18f, 0.16f, 0.13f),
                 Eigen::Vector3f(0.85f, 0.82f, 0.76f));
}

Eigen::Vector3f PavingAlbedo(const Eigen::Vector2f& p, uint32_t seed, float footprint) {
  uint32_t stone;
  const float joint = Blocks(p, 1.3f, 0.9f, 0.05f, seed, footprint, &stone);
  // Per-stone tints fade to their mean when stones shrink to a few pixels (no aliasing).
  const float lod = LodWeight(0.9f, footprint);
  const float tint = 0.97f + lod * 0.5f * (UnitFloat(stone) - 0.5f);
  const float warm = lod * 0.06f * (UnitFloat(Mix32(stone)) - 0.5f);
  Eigen::Vector3f color = tint * Eigen::Vector3f(0.66f + warm, 0.62f, 0.55f - warm);
  color *= Detail(p, seed + 1, 1.2f, 8, footprint, 2.0f);
  color = Speckle(p, seed + 2, footprint, 0.28f, color, Eigen::Vector3f(0.25f, 0.23f, 0.2f),
                  Eigen::Vector3f(0.9f, 0.88f, 0.84f));
  return Mix(color, Eigen::Vector3f(0.2f, 0.19f, 0.17f), joint);
}

Eigen::Vector3f MarbleAlbedo(const Eigen::Vector2f& p, uint32_t seed, float footprint) {
  const float tint = 0.85f + 0.25f * UnitFloat(seed);
  Eigen::Vector3f color = tint * Eigen::Vector3f(0.82f, 0.77f, 0.68f);
  // Veins: level lines of a warped linear field, drawn as thin dark lines.
  const float warp = Fbm(p, seed + 3, 1.6f, 5, footprint);
  const float phase = 1.1f * (0.6f * p.x() + 0.8f * p.y()) + 7.0f * warp;
  const float line = std::abs(std::sin(std::numbers::pi_v<float> * phase));
  const float vein = (1.0f - SmoothStep(0.0f, 0.12f, line)) * LodWeight(0.12f, footprint);
  color *= Detail(p, seed + 1, 0.9f, 7, footprint, 1.8f);
  color = Mix(color, 0.4f * color, 0.8f * vein);
  return Speckle(p, seed + 2, footprint, 0.2f, color, Eigen::Vector3f(0.3f, 0.32f, 0.26f),
                 Eigen::Vector3f(0.95f, 0.93f, 0.88f));
}

Eigen::Vector3f ColumnAlbedo(const Eigen::Vector2f& p, uint32_t seed, float footprint,
                             float radius) {
  constexpr int kFlutes = 20;
  const float flute_period = 2.0f * std::numbers::pi_v<float> * radius / kFlutes;
  const float flute = std::cos(2.0f * std::numbers::pi_v<float> * p.x() / flute_period);
  Eigen::Vector3f color = Eigen::Vector3f(0.84f, 0.8f, 0.72f);
  color *= 1.0f + 0.12f * flute * LodWeight(flute_period, footprint);
  // Vertical weathering streaks: noise stretched along the column.
  const Eigen::Vector2f stretched(4.0f * p.x(), 0.5f * p.y());
  color *= Detail(stretched, seed + 4, 1.5f, 5, 4.0f * footprint, 1.4f);
  color *= Detail(p, seed + 1, 0.6f, 6, footprint, 1.6f);
  return Speckle(p, seed + 2, footprint, 0.16f, color, Eigen::Vector3f(0.28f, 0.27f, 0.24f),
                 Eigen::Vector3f(0.96f, 0.94f, 0.9f));
}

Eigen::Vector3f AshlarAlbedo(const Eigen::Vector2f& p, uint32_t seed, float footprint) {
  uint32_t block;
  const float joint = Blocks(p, 0.9f, 0.45f, 0.04f, seed, footprint, &block);
  const float lod = LodWeight(0.45f, footprint);
  const float tint = 0.925f + lod * 0.45f * (UnitFloat(block) - 0.5f);
  const float hue = lod * 0.1f * (UnitFloat(Mix32(block + 7)) - 0.5f);
  Eigen::Vector3f color = tint * Eigen::Vector3f(0.74f + hue, 0.66f, 0.54f - hue);
  color *= Detail(p, seed + 1, 0.7f, 7, footprint, 1.9f);
  color = Speckle(p, seed + 2, footprint, 0.18f, color, Eigen::Vector3f(0.22f, 0.2f, 0.18f),
                  Eigen::Vector3f(0.92f, 0.9f, 0.84f));
  return Mix(color, Eigen::Vector3f(0.24f, 0.22f, 0.2f), joint);
}

Eigen::Vector3f RoofTileAlbedo(const Eigen::Vector2f& p, uint32_t seed, float footprint) {
  uint32_t tile;
  const float joint = Blocks(p, 0.42f, 0.32f, 0.035f, seed, footprint, &tile);
  const float tint = 0.925f + LodWeight(0.32f, footprint) * 0.55f * (UnitFloat(tile) - 0.5f);
  Eigen::Vector3f color = tint * Eigen::Vector3f(0.68f, 0.33f, 0.2f);
  color *= Detail(p, seed + 1, 1.5f, 7, footprint, 1.8f);
  color = Speckle(p, seed + 2, footprint, 0.3f, color, Eigen::Vector3f(0.25f, 0.3f, 0.18f),
                  Eigen::Vector3f(0.85f, 0.75f, 0.6f));
  return Mix(color, Eigen::Vector3f(0.18f, 0.1f, 0.08f), joint);
}

Eigen::Vector3f AsphaltAlbedo(const Eigen::Vector2f& p, float along, float across, uint32_t seed,
                              float footprint) {
  Eigen::Vector3f color = Eigen::Vector3f(0.3f, 0.3f, 0.31f);
  color *= Detail(p, seed + 1, 3.0f, 8, footprint, 1.2f);
  color = Speckle(p, seed + 2, footprint, 0.5f, color, Eigen::Vector3f(0.15f, 0.15f, 0.15f),
                  Eigen::Vector3f(0.55f, 0.55f, 0.53f));
  // The centre line: 3 m dashes every 6 m, 15 cm wide.
  const float dash =
      SmoothStep(0.0f, 0.2f, 1.5f - std::abs(std::fmod(std::abs(along), 6.0f) - 3.0f));
  const float width =
      LodWeight(0.3f, footprint) * (1.0f - SmoothStep(0.06f, 0.09f, std::abs(across)));
  return Mix(color, Eigen::Vector3f(0.88f, 0.86f, 0.8f), dash * width);
}

Eigen::Vector3f FieldAlbedo(const Eigen::Vector2f& p, uint32_t crop_seed, uint32_t seed,
                            float footprint) {
  const float spacing = 0.6f + 0.8f * UnitFloat(Mix32(crop_seed + 11));
  const Eigen::Vector3f soil(0.5f, 0.4f, 0.28f);
  const Eigen::Vector3f crop =
      Mix(Eigen::Vector3f(0.35f, 0.5f, 0.2f), Eigen::Vector3f(0.72f, 0.64f, 0.33f),
          UnitFloat(Mix32(crop_seed + 12)));
  // Rows along u: a soft stripe per row, fading to the mean colour when rows are sub-pixel.
  const float row = 0.5f + 0.5f * std::cos(2.0f * std::numbers::pi_v<float> * p.y() / spacing);
  const float lod = LodWeight(spacing, footprint);
  Eigen::Vector3f color = Mix(soil, crop, 0.55f + lod * (SmoothStep(0.3f, 0.7f, row) - 0.5f));
  color *= Detail(p, seed + 1, 6.0f, 9, footprint, 1.6f);
  return Speckle(p, seed + 2, footprint, 0.7f, color, Eigen::Vector3f(0.2f, 0.2f, 0.12f),
                 Eigen::Vector3f(0.8f, 0.78f, 0.6f));
}

}  // namespace parallax
