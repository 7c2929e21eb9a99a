// Noise, solid materials and the texture atlas: determinism, ranges, feature richness (SIFT)
// and uniform texel density on steep surfaces.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "auv/sim/common/yaml_section.h"
#include "auv/sim/worldgen/atlas_baker.h"
#include "auv/sim/worldgen/materials.h"
#include "auv/sim/worldgen/noise.h"
#include "auv/sim/worldgen/shapes.h"

namespace auv::sim::worldgen {
namespace {

using Eigen::Vector3f;

TEST(NoiseTest, SameSeedSameValuesOtherSeedOtherValues) {
  const GradientNoise a(7), b(7), c(8);
  int differing = 0;
  for (int i = 0; i < 200; ++i) {
    const Vector3f p(0.37f * i, -0.11f * i + 3.0f, 0.05f * i);
    EXPECT_EQ(a.noise(p), b.noise(p));
    EXPECT_EQ(a.fbm(p, 2.0f, 4), b.fbm(p, 2.0f, 4));
    differing += std::abs(a.noise(p) - c.noise(p)) > 1e-3f;
  }
  EXPECT_GT(differing, 150);
}

TEST(NoiseTest, BoundedZeroMeanAndContinuous) {
  const GradientNoise noise(3);
  double sum = 0.0;
  float lo = 0.0f, hi = 0.0f, steepest = 0.0f;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const Vector3f p(0.0713f * i, 0.0291f * i - 40.0f, 0.0177f * i + 5.0f);
    const float v = noise.noise(p);
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    sum += v;
    // Gradient noise is smooth: a step of 1e-3 lattice units changes it by less than ~1e-2.
    steepest = std::max(steepest, std::abs(noise.noise(p + Vector3f(1e-3f, 0, 0)) - v) / 1e-3f);
  }
  EXPECT_GT(lo, -1.1f);
  EXPECT_LT(hi, 1.1f);
  EXPECT_LT(hi - lo, 2.2f);
  EXPECT_GT(hi - lo, 1.0f);  // not flat
  EXPECT_NEAR(sum / n, 0.0, 0.05);
  EXPECT_LT(steepest, 4.0f);
}

TEST(NoiseTest, OctavesBelowTheMinimumWavelengthAreLeftOut) {
  const GradientNoise noise(5);
  const Vector3f p(1.3f, 2.9f, -0.4f);
  // With min_wavelength above the first octave's half, only the first octave remains.
  EXPECT_FLOAT_EQ(noise.fbm(p, 1.0f, 6, 0.5f, 0.9f), noise.fbm(p, 1.0f, 1));
  EXPECT_NE(noise.fbm(p, 1.0f, 6), noise.fbm(p, 1.0f, 1));
}

// Keypoints SIFT finds on a 1024 x 1024 sample of a material at the given texel size.
size_t siftKeypoints(Material material, float texel, bool vertical) {
  const cv::Mat image = renderMaterialSample(material, 11, texel, 1024, vertical);
  cv::Mat gray;
  cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  std::vector<cv::KeyPoint> keypoints;
  cv::SIFT::create()->detect(gray, keypoints);
  return keypoints.size();
}

TEST(MaterialTest, RockGivesSiftHundredsOfFeaturesAtOneToTwoCentimetresPerTexel) {
  EXPECT_GE(siftKeypoints(Material::ROCK, 0.015f, true), 500u);
  EXPECT_GE(siftKeypoints(Material::ROCK, 0.02f, false), 500u);
  EXPECT_GE(siftKeypoints(Material::CONCRETE, 0.02f, true), 500u);
}

TEST(MaterialTest, DeterministicPerSeedAndInRange) {
  const cv::Mat a = renderMaterialSample(Material::ROCK, 4, 0.02f, 64);
  const cv::Mat b = renderMaterialSample(Material::ROCK, 4, 0.02f, 64);
  const cv::Mat c = renderMaterialSample(Material::ROCK, 5, 0.02f, 64);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a, c, cv::NORM_L1), 0.0);
  const MaterialShader shader(1);
  for (Material m : {Material::ROCK, Material::CONCRETE, Material::SAND}) {
    for (int i = 0; i < 100; ++i) {
      const Vector3f rgb =
          shader.shade(m, Vector3f(0.3f * i, -0.2f * i, -0.1f * i), Vector3f(0, 0, 1), 0.02f);
      EXPECT_TRUE((rgb.array() >= 0.0f).all() && (rgb.array() <= 1.0f).all()) << materialName(m);
    }
  }
}

// A vertical cylinder wall of radius r and height h, as a closed band.
SurfaceGrid cylinder(float radius, float height, int columns, int rows, float texel) {
  SurfaceGrid grid(rows, columns, true, Material::ROCK, texel);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      const float a = 2.0f * static_cast<float>(M_PI) * c / columns;  // counter-clockwise
      grid.at(r, c) =
          Vector3f(radius * std::cos(a), radius * std::sin(a), -height + height * r / (rows - 1));
    }
  }
  computeNormals(grid);
  return grid;
}

TEST(AtlasTest, TexelDensityIsUniformOnWallsAndFloors) {
  const float texel = 0.02f;
  std::vector<SurfaceGrid> grids{cylinder(3.0f, 6.0f, 48, 13, texel),
                                 planarGrid(Vector3f(5, 5, -6), Vector3f(4, 0, 0),
                                            Vector3f(0, 3, 0), 0.5f, Material::SAND, texel)};
  AtlasOptions options;
  options.max_texture_size = 4096;
  AtlasReport report;
  const Mesh mesh = bakeTexturedMesh(grids, options, &report);
  ASSERT_TRUE(mesh.hasTexture());
  EXPECT_FLOAT_EQ(report.texel_scale, 1.0f);
  ASSERT_EQ(mesh.triangle_uvs.size(), 3 * mesh.triangles.size());
  const double w = mesh.texture.cols, h = mesh.texture.rows;
  double area_3d = 0.0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    const Vector3f& a = mesh.vertices[tri[0]];
    const double area = 0.5 * (mesh.vertices[tri[1]] - a).cross(mesh.vertices[tri[2]] - a).norm();
    Eigen::Vector2d uv[3];
    for (int k = 0; k < 3; ++k) {
      uv[k] = mesh.triangle_uvs[3 * t + k].cast<double>().cwiseProduct(Eigen::Vector2d(w, h));
      ASSERT_GE(uv[k].x(), 0.0);
      ASSERT_LE(uv[k].x(), w);
      ASSERT_GE(uv[k].y(), 0.0);
      ASSERT_LE(uv[k].y(), h);
    }
    const Eigen::Vector2d e1 = uv[1] - uv[0], e2 = uv[2] - uv[0];
    const double area_px = 0.5 * std::abs(e1.x() * e2.y() - e1.y() * e2.x());
    // Texels per metre: at least 1/texel, and not much more (cells round up to whole texels).
    const double density = std::sqrt(area_px / area);
    EXPECT_GE(density, 0.98 / texel) << "triangle " << t;
    EXPECT_LE(density, 1.25 / texel) << "triangle " << t;
    area_3d += area;
  }
  EXPECT_NEAR(area_3d, 2 * M_PI * 3.0 * 6.0 + 12.0, 0.5);  // chords make it a bit smaller
}

TEST(AtlasTest, TrianglesFaceOutwardAndTexelsGrowToFitTheAtlas) {
  std::vector<SurfaceGrid> grids{cylinder(3.0f, 6.0f, 48, 13, 0.01f)};
  AtlasOptions options;
  options.max_texture_size = 256;
  options.max_cell_size = 128;
  AtlasReport report;
  const Mesh mesh = bakeTexturedMesh(grids, options, &report);
  EXPECT_LE(mesh.texture.cols, 256);
  EXPECT_LE(mesh.texture.rows, 256);
  EXPECT_GT(report.texel_scale, 5.0f);  // 113 m^2 at 1 cm needs far more than 256^2 texels
  for (const Eigen::Vector3i& tri : mesh.triangles) {
    const Vector3f a = mesh.vertices[tri[0]], b = mesh.vertices[tri[1]], c = mesh.vertices[tri[2]];
    const Vector3f normal = (b - a).cross(c - a);
    const Vector3f centre = (a + b + c) / 3.0f;
    EXPECT_GT(normal.dot(Vector3f(centre.x(), centre.y(), 0)), 0.0f);
  }
}

TEST(AtlasTest, CollapsedCrestsAndDisabledQuadsAreLeftOut) {
  RockSpec rock;
  rock.ridge = {Eigen::Vector2f(0, 0)};
  rock.half_width = [](float, int) { return 2.0f; };
  rock.spacing = 0.5f;
  rock.texel_size = 0.05f;
  std::vector<SurfaceGrid> grids{buildRock(rock)};
  SurfaceGrid floor = planarGrid(Vector3f(-5, -5, -10), Vector3f(10, 0, 0), Vector3f(0, 10, 0),
                                 1.0f, Material::SAND, 0.05f);
  floor.quad_enabled.assign(100, 1);
  for (int i = 0; i < 50; ++i) floor.quad_enabled[i] = 0;
  grids.push_back(floor);
  const Mesh mesh = bakeTexturedMesh(grids, AtlasOptions());
  size_t floor_triangles = 0;
  for (const Eigen::Vector3i& tri : mesh.triangles) {
    const Vector3f a = mesh.vertices[tri[0]], b = mesh.vertices[tri[1]], c = mesh.vertices[tri[2]];
    EXPECT_GT((b - a).cross(c - a).norm(), 1e-7f);
    floor_triangles += std::abs(a.z() + 10.0f) < 1e-4f && std::abs(b.z() + 10.0f) < 1e-4f &&
                       std::abs(c.z() + 10.0f) < 1e-4f;
  }
  EXPECT_EQ(floor_triangles, 100u);  // half of the 100 quads, two triangles each
}

TEST(AtlasTest, RejectsBadOptions) {
  AtlasOptions options;
  options.max_texture_size = 10;
  EXPECT_THROW(options.check(), ConfigError);
  options = AtlasOptions();
  options.padding = -1;
  EXPECT_THROW(options.check(), ConfigError);
}

TEST(RockTest, WidthAtQueryDepthFollowsTheDesignWithinTheRoughness) {
  RockSpec rock;
  rock.ridge = {Eigen::Vector2f(0, 0), Eigen::Vector2f(20, 0)};
  rock.half_width = [](float, int side) { return side > 0 ? 6.0f : 4.0f; };
  rock.seabed_z = -10.0f;
  rock.bottom_z = -11.0f;
  rock.top_z = 1.0f;
  rock.roughness = 0.4f;
  rock.spacing = 0.25f;
  const SurfaceGrid grid = buildRock(rock);
  const float fraction = rockWidthFraction(rock, -3.0f);
  EXPECT_GT(fraction, 0.5f);
  EXPECT_LT(fraction, 1.0f);
  // Along the straight part, points near z = -3 lie within roughness of the designed walls.
  int checked = 0;
  for (const Vector3f& p : grid.points) {
    if (std::abs(p.z() + 3.0f) > 0.05f || p.x() < 1.0f || p.x() > 19.0f) continue;
    const float designed = p.y() > 0 ? 6.0f * fraction : 4.0f * fraction;
    EXPECT_NEAR(std::abs(p.y()), designed, rock.roughness + 0.05f) << p.transpose();
    ++checked;
  }
  EXPECT_GT(checked, 20);
}

}  // namespace
}  // namespace auv::sim::worldgen
