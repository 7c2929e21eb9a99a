#include "auv/sim/worldgen/materials.h"

#include <algorithm>
#include <cmath>

namespace auv::sim::worldgen {
namespace {

using Eigen::Vector3f;

Vector3f mix(const Vector3f& a, const Vector3f& b, float t) { return a + (b - a) * t; }

// Light from above and slightly to the side: relief is shaded by the slope of a small height
// field along this direction, which gives the embossed look of real rock under a lamp.
const Vector3f kLightDirection = Vector3f(0.35f, 0.25f, 0.90f).normalized();

// Slope (m/m) towards the light of a height field `amplitude` * fbm: shading by it gives the
// embossed look of real rock under a lamp.
float reliefSlope(const GradientNoise& noise, const Vector3f& p, float wavelength, int octaves,
                  float amplitude, float fine = 0.0f) {
  const float step = std::max(0.5f * fine, 0.004f);
  const float h0 = noise.fbm(p, wavelength, octaves, 0.6f, fine);
  const float h1 = noise.fbm(p + step * kLightDirection, wavelength, octaves, 0.6f, fine);
  return amplitude * (h1 - h0) / step;
}

float reliefShade(float slope, float strength) {
  return std::min(1.45f, std::max(0.55f, 1.0f + strength * slope));
}

// Thin dark lines where a noise field crosses zero (cracks, joints). `width` is the |noise|
// below which the line is fully dark; widened by the texel so lines never alias away.
float zeroLine(float value, float width, float texel_in_noise_units) {
  const float w = width + texel_in_noise_units;
  return 1.0f - smoothStep(0.5f * w, w, std::abs(value));
}

}  // namespace

std::string materialName(Material material) {
  switch (material) {
    case Material::ROCK:
      return "rock";
    case Material::CONCRETE:
      return "concrete";
    case Material::SAND:
      return "sand";
  }
  return "?";
}

MaterialShader::MaterialShader(uint64_t seed)
    : colour_(seed * 7 + 1),
      relief_(seed * 7 + 2),
      grain_(seed * 7 + 3),
      cracks_(seed * 7 + 4),
      life_(seed * 7 + 5) {}

// Field indices of CoarseFields per material.
namespace {
enum RockField { R_TONE, R_HUE, R_JOINT, R_HAIRLINE_GATE, R_CORALLINE, R_TURF, R_RELIEF };
enum ConcreteField { C_TONE, C_RUST, C_STAIN, C_ALGAE, C_RELIEF };
enum SandField { S_TONE, S_RIPPLE_WARP, S_MEADOW };
}  // namespace

CoarseFields MaterialShader::coarse(Material material, const Vector3f& p, const Vector3f& n) const {
  CoarseFields f;
  float* v = f.value;
  switch (material) {
    case Material::ROCK: {
      v[R_TONE] = colour_.fbm(p, 4.0f, 2);
      v[R_HUE] = colour_.fbm(p + Vector3f(51.3f, -7.2f, 3.3f), 9.0f, 2);
      const Vector3f warp(colour_.noise(p * 0.9f), colour_.noise(p * 0.9f + Vector3f(9, 1, 4)), 0);
      // Joints: zero crossings of a noise 2.5 m wide, kept where a second field is positive.
      v[R_JOINT] = cracks_.noise(p * (1.0f / 2.5f) + 0.3f * warp);
      v[R_HAIRLINE_GATE] = cracks_.noise(p * (1.0f / 1.2f) + Vector3f(1, 1, 1));
      v[R_CORALLINE] = life_.fbm(p, 0.8f, 2);
      v[R_TURF] =
          life_.fbm(p + Vector3f(13.1f, 2.9f, -6.4f), 1.3f, 2, 0.55f) + 1.2f * (n.z() - 0.45f);
      v[R_RELIEF] = reliefSlope(relief_, p, 0.8f, 2, 0.05f);
      break;
    }
    case Material::CONCRETE: {
      v[C_TONE] = colour_.fbm(p, 3.0f, 3);
      // Streaks: stretched along the vertical, so they run down the faces.
      const Vector3f streak(p.x() / 0.6f, p.y() / 0.6f, p.z() / 4.0f);
      v[C_RUST] = colour_.fbm(streak + Vector3f(21, 4, 7), 1.0f, 2);
      v[C_STAIN] = colour_.fbm(streak + Vector3f(-9, 14, 2), 1.0f, 2);
      v[C_ALGAE] = life_.fbm(p, 0.9f, 2) + 0.3f * n.z();
      v[C_RELIEF] = reliefSlope(relief_, p, 0.6f, 1, 0.01f);
      break;
    }
    case Material::SAND: {
      v[S_TONE] = colour_.fbm(p, 6.0f, 3);
      v[S_RIPPLE_WARP] = colour_.fbm(p, 3.0f, 2);
      v[S_MEADOW] = life_.fbm(p, 7.0f, 3);
      break;
    }
  }
  return f;
}

Vector3f MaterialShader::shadeFine(Material material, const Vector3f& point, const Vector3f& normal,
                                   float texel_size, const CoarseFields& fields) const {
  Vector3f c;
  switch (material) {
    case Material::ROCK:
      c = rock(point, normal, texel_size, fields);
      break;
    case Material::CONCRETE:
      c = concrete(point, normal, texel_size, fields);
      break;
    case Material::SAND:
      c = sand(point, normal, texel_size, fields);
      break;
  }
  return c.cwiseMax(0.0f).cwiseMin(1.0f);
}

Vector3f MaterialShader::rock(const Vector3f& p, const Vector3f& n, float texel,
                              const CoarseFields& fields) const {
  const float* f = fields.value;
  const float fine = 2.0f * texel;                       // shortest wavelength worth drawing
  const float light = smoothStep(-12.0f, -1.0f, p.z());  // more algae where there is more light

  // Tone: grey granite, warm ochre weathering, darker and lighter areas of a few metres.
  Vector3f c = mix(Vector3f(0.47f, 0.46f, 0.43f), Vector3f(0.58f, 0.48f, 0.35f),
                   smoothStep(-0.3f, 0.6f, f[R_HUE]));
  c *= 0.80f + 0.24f * f[R_TONE];

  // Mineral grain: light feldspar and dark mica specks a few texels wide, and blotches.
  if (fine < 0.05f) {
    const float g = grain_.noise(p * (1.0f / 0.022f));
    c = mix(c, Vector3f(0.78f, 0.75f, 0.69f), 0.6f * smoothStep(0.30f, 0.44f, g));
    c = mix(c, Vector3f(0.13f, 0.12f, 0.12f), 0.7f * smoothStep(-0.34f, -0.48f, g));
  }
  if (fine < 0.14f) {
    c *= 1.0f + 0.14f * grain_.noise(p * (1.0f / 0.07f) + Vector3f(3.1f, 7.7f, 1.3f));
  }

  // Relief lit from above: a coarse octave from the slow fields, a fine one here.
  const float fine_relief =
      0.2f > 2.0f * fine ? reliefSlope(relief_, p, 0.2f, 1, 0.012f, fine) : 0.0f;
  c *= reliefShade(f[R_RELIEF] + fine_relief, 3.0f);

  // Cracks: long joints every metre or two, and intermittent hairline cracks.
  const float joint = zeroLine(f[R_JOINT], 0.02f, texel / 2.5f * 2.0f) *
                      smoothStep(-0.25f, -0.05f, f[R_HAIRLINE_GATE]);
  float hairline = 0.0f;
  if (fine < 0.1f && f[R_HAIRLINE_GATE] > 0.1f) {
    hairline = zeroLine(cracks_.noise(p * (1.0f / 0.6f) + Vector3f(4.2f, 8.1f, 0.6f)), 0.012f,
                        texel / 0.6f * 2.0f) *
               smoothStep(0.1f, 0.4f, f[R_HAIRLINE_GATE]);
  }
  c *= 1.0f - 0.68f * std::max(joint, 0.6f * hairline);

  // Coralline algae crusts: pink-mauve patches with a mottled interior.
  const float coralline_mask = smoothStep(0.42f, 0.52f, f[R_CORALLINE] + 0.15f * light);
  if (coralline_mask > 0.0f) {
    const float mottle = fine < 0.06f ? life_.noise(p * (1.0f / 0.03f)) : 0.0f;
    c = mix(c, Vector3f(0.64f, 0.45f, 0.50f) * (0.88f + 0.22f * mottle), 0.85f * coralline_mask);
  }

  // Turf algae on surfaces facing up, denser where there is more light.
  const float turf_mask = smoothStep(0.15f, 0.35f, f[R_TURF] + 0.4f * (light - 0.5f));
  if (turf_mask > 0.0f) {
    // Tufts: light and dark clumps a few centimetres across; the rock shows through a little.
    const float tuft = fine < 0.07f ? life_.noise(p * (1.0f / 0.035f) + Vector3f(7, 3, 5)) : 0.0f;
    const Vector3f turf_colour = mix(Vector3f(0.22f, 0.29f, 0.12f), Vector3f(0.50f, 0.47f, 0.24f),
                                     smoothStep(-0.45f, 0.45f, tuft));
    c = mix(c, turf_colour, 0.8f * turf_mask);
  }

  // Sponges: scattered orange, yellow or red blobs of 5-20 cm.
  const float sponge = life_.noise(p * (1.0f / 0.18f) + Vector3f(-8.3f, 4.4f, 2.2f));
  const float sponge_mask = smoothStep(0.52f, 0.60f, sponge);
  if (sponge_mask > 0.0f) {
    const Vector3f sponge_colour =
        f[R_HUE] > 0.0f ? Vector3f(0.88f, 0.58f, 0.17f) : Vector3f(0.72f, 0.22f, 0.16f);
    c = mix(c, sponge_colour, 0.9f * sponge_mask);
  }

  // Barnacles and bryozoans (small pale dots) and pits (small dark holes), from one field.
  if (fine < 0.045f) {
    const float dots = life_.noise(p * (1.0f / 0.03f) + Vector3f(2.2f, -9.1f, 6.6f));
    c = mix(c, Vector3f(0.86f, 0.84f, 0.77f), 0.8f * smoothStep(0.50f, 0.60f, dots));
    c *= 1.0f - 0.6f * smoothStep(-0.52f, -0.64f, dots);
  }
  (void)n;
  return c;
}

Vector3f MaterialShader::concrete(const Vector3f& p, const Vector3f& n, float texel,
                                  const CoarseFields& fields) const {
  const float* f = fields.value;
  const float fine = 2.0f * texel;
  const float light = smoothStep(-11.0f, -0.5f, p.z());

  Vector3f c = Vector3f(0.61f, 0.60f, 0.56f) * (0.88f + 0.15f * f[C_TONE]);

  // Aggregate: light and dark stones showing through the cement paste.
  if (fine < 0.04f) {
    const float g = grain_.noise(p * (1.0f / 0.018f));
    c = mix(c, Vector3f(0.80f, 0.78f, 0.72f), 0.65f * smoothStep(0.35f, 0.48f, g));
    c = mix(c, Vector3f(0.32f, 0.31f, 0.29f), 0.65f * smoothStep(-0.40f, -0.52f, g));
  }
  if (fine < 0.12f) c *= 1.0f + 0.10f * grain_.noise(p * (1.0f / 0.06f) + Vector3f(5, 2, 9));

  // Bugholes: small air voids left by the formwork.
  if (fine < 0.09f) {
    const float hole = grain_.noise(p * (1.0f / 0.045f) + Vector3f(-3.3f, 6.1f, 2.4f));
    c = mix(c, Vector3f(0.17f, 0.17f, 0.16f), smoothStep(0.55f, 0.66f, hole));
  }

  const float fine_relief =
      0.15f > 2.0f * fine ? reliefSlope(relief_, p, 0.15f, 1, 0.006f, fine) : 0.0f;
  c *= reliefShade(f[C_RELIEF] + fine_relief, 4.0f);

  // Lift joints every 1.5 m of height and formwork joints every 3 m along vertical faces.
  auto jointDistance = [](float coordinate, float spacing) {
    return std::abs(coordinate / spacing - std::floor(coordinate / spacing + 0.5f)) * spacing;
  };
  float joint = 1.0f - smoothStep(0.006f, 0.006f + texel, jointDistance(p.z(), 1.5f));
  if (std::abs(n.z()) < 0.5f) {
    const float along = std::abs(n.x()) > std::abs(n.y()) ? p.y() : p.x();
    joint = std::max(joint, 1.0f - smoothStep(0.005f, 0.005f + texel, jointDistance(along, 3.0f)));
  }
  c *= 1.0f - 0.45f * joint;

  // Rust and dark water streaks running down the faces.
  c = mix(c, Vector3f(0.53f, 0.37f, 0.24f), 0.55f * smoothStep(0.35f, 0.65f, f[C_RUST]));
  c *= 1.0f - 0.28f * smoothStep(0.25f, 0.6f, f[C_STAIN]);

  // Green algae patches (more near the surface and on tops) and small dark algae spots.
  const float algae_mask = smoothStep(0.10f, 0.30f, f[C_ALGAE] + 0.7f * (light - 0.5f));
  if (algae_mask > 0.0f) {
    const float tuft = fine < 0.1f ? life_.noise(p * (1.0f / 0.04f) + Vector3f(1, 8, 3)) : 0.0f;
    c = mix(c,
            mix(Vector3f(0.27f, 0.40f, 0.20f), Vector3f(0.40f, 0.43f, 0.22f), 0.5f + 0.5f * tuft),
            0.85f * algae_mask);
  }
  if (fine < 0.14f) {
    const float spot = life_.noise(p * (1.0f / 0.07f) + Vector3f(-4.1f, 2.6f, 9.3f));
    c = mix(c, Vector3f(0.24f, 0.29f, 0.15f), 0.85f * smoothStep(0.50f, 0.60f, spot));
  }
  // Barnacles near the waterline.
  if (fine < 0.04f && p.z() > -3.0f) {
    const float dots = life_.noise(p * (1.0f / 0.025f) + Vector3f(6, -2, 4));
    c = mix(c, Vector3f(0.88f, 0.86f, 0.80f),
            0.85f * smoothStep(0.45f, 0.55f, dots) * smoothStep(-3.0f, -1.5f, p.z()));
  }
  return c;
}

Vector3f MaterialShader::sand(const Vector3f& p, const Vector3f& /*n*/, float texel,
                              const CoarseFields& fields) const {
  const float* f = fields.value;
  const float fine = 2.0f * texel;
  Vector3f c = Vector3f(0.74f, 0.68f, 0.54f) * (0.85f + 0.15f * f[S_TONE]);

  // Wave ripples about 35 cm apart, their crests bent by large-scale noise.
  const float ripple_wavelength = 0.35f;
  if (ripple_wavelength > 2.0f * fine) {
    const float phase = (0.8f * p.x() + 0.6f * p.y()) / ripple_wavelength + 1.5f * f[S_RIPPLE_WARP];
    const float s = std::sin(6.2831853f * phase);
    c *= 1.0f + 0.09f * (s - 0.3f * std::sin(12.566371f * phase));
  }

  // Grit: pale shell fragments and dark grains; scattered pebbles.
  if (fine < 0.06f) {
    const float g = grain_.noise(p * (1.0f / 0.03f));
    c = mix(c, Vector3f(0.93f, 0.91f, 0.85f), 0.7f * smoothStep(0.45f, 0.56f, g));
    c = mix(c, Vector3f(0.35f, 0.32f, 0.27f), 0.7f * smoothStep(-0.45f, -0.56f, g));
  }
  if (fine < 0.2f) {
    const float pebble = grain_.noise(p * (1.0f / 0.12f) + Vector3f(4, 4, 1));
    c = mix(c, Vector3f(0.52f, 0.51f, 0.47f), 0.8f * smoothStep(0.60f, 0.68f, pebble));
  }

  // Seagrass meadows: dark olive patches of streaky blades.
  const float meadow_mask = smoothStep(0.35f, 0.50f, f[S_MEADOW]);
  if (meadow_mask > 0.0f) {
    const float blades =
        fine < 0.1f ? life_.noise(Vector3f(p.x() / 0.03f, p.y() / 0.25f, p.z())) : 0.0f;
    c = mix(c, Vector3f(0.20f, 0.27f, 0.12f) * (0.85f + 0.3f * blades), 0.9f * meadow_mask);
  }
  return c;
}

cv::Mat renderMaterialSample(Material material, uint64_t seed, float texel_size, int size,
                             bool vertical, const Eigen::Vector3f& origin) {
  const MaterialShader shader(seed);
  cv::Mat image(size, size, CV_8UC3);
  const Vector3f normal = vertical ? Vector3f(1, 0, 0) : Vector3f(0, 0, 1);
  for (int row = 0; row < size; ++row) {
    auto* pixels = image.ptr<cv::Vec3b>(row);
    for (int col = 0; col < size; ++col) {
      // Vertical: columns run west to east (mesh -y), rows down in depth; horizontal: a map.
      const Vector3f point = vertical ? origin + Vector3f(0, -col * texel_size, -row * texel_size)
                                      : origin + Vector3f(-row * texel_size, -col * texel_size, 0);
      const Vector3f rgb = shader.shade(material, point, normal, texel_size);
      pixels[col] = cv::Vec3b(static_cast<uchar>(rgb.z() * 255.0f + 0.5f),
                              static_cast<uchar>(rgb.y() * 255.0f + 0.5f),
                              static_cast<uchar>(rgb.x() * 255.0f + 0.5f));
    }
  }
  return image;
}

}  // namespace auv::sim::worldgen
