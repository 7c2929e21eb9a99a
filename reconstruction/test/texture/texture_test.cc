// Texturing (docs/paper.md §3.7, Waechter et al. 2014) on synthetic scenes with known colours:
// coverage and visibility, MRF against greedy, photo-consistency against a fish, seam
// levelling across an exposure change, OBJ round trip, re-rendering fidelity.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <random>

#include <open3d/geometry/TriangleMesh.h>
#include <open3d/io/TriangleMeshIO.h>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/texture/texturer.h"
#include "synthetic_scene.h"

namespace fs = std::filesystem;
using namespace auv::recon;
using namespace auv::recon::texture;

namespace {

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("auv_recon_texture_" + std::to_string(::getpid()) + "_" +
                                        std::to_string(std::random_device{}()));
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

struct Scene {
  FaceMesh mesh;
  std::vector<ViewGeometry> views;
  std::vector<cv::Mat3b> images;
  ImageLoader loader() const {
    return [this](int v) { return cv::Mat(images[v]); };
  }
};

/// Independent visibility: the face's vertices project inside the image, it faces the camera,
/// and the ray from the camera to its centroid meets no other face first (brute force).
bool seesFace(const FaceMesh& mesh, const ViewGeometry& view, int f) {
  const Eigen::Vector3i& t = mesh.faces[f];
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d c = view.toCamera(mesh.vertices[t(k)]);
    if (c.z() <= 0) return false;
    const Eigen::Vector2d p = view.project(c);
    if (p.x() < 1 || p.y() < 1 || p.x() > view.width() - 2 || p.y() > view.height() - 2) {
      return false;
    }
  }
  const Eigen::Vector3d centroid =
      (mesh.vertices[t(0)] + mesh.vertices[t(1)] + mesh.vertices[t(2)]) / 3.0;
  const Eigen::Vector3d origin = view.center();
  const Eigen::Vector3d dir = centroid - origin;
  if (mesh.face_normals[f].dot(-dir.normalized()) <= 0.1) return false;
  for (size_t g = 0; g < mesh.faces.size(); ++g) {  // Moeller-Trumbore
    if (static_cast<int>(g) == f) continue;
    const Eigen::Vector3d& a = mesh.vertices[mesh.faces[g](0)];
    const Eigen::Vector3d e1 = mesh.vertices[mesh.faces[g](1)] - a;
    const Eigen::Vector3d e2 = mesh.vertices[mesh.faces[g](2)] - a;
    const Eigen::Vector3d p = dir.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-12) continue;
    const Eigen::Vector3d s = origin - a;
    const double u = s.dot(p) / det;
    if (u < 0 || u > 1) continue;
    const Eigen::Vector3d q = s.cross(e1);
    const double v = dir.dot(q) / det;
    if (v < 0 || u + v > 1) continue;
    const double hit = e2.dot(q) / det;
    if (hit > 1e-6 && hit < 1 - 1e-3) return false;  // something before the centroid
  }
  return true;
}

TextureOptions quietOptions() {
  TextureOptions options;
  options.atlas.max_page_size = 1024;
  return options;
}

/// Mean colour jump across the seams of a textured model: for every seam edge, the model's
/// colours just inside the two faces at the edge's midpoint.
double meanSeamJump(const TexturedModel& model, const FaceMesh& mesh,
                    const std::vector<int>& labels) {
  double sum = 0;
  size_t count = 0;
  for (const SeamEdge& seam : findSeamEdges(mesh, labels)) {
    Eigen::Vector3f side[2];
    int k = 0;
    for (int f : {seam.face_a, seam.face_b}) {
      // Barycentrics of the point 15 % of the way from the edge midpoint to the centroid.
      Eigen::Vector3d w = Eigen::Vector3d::Constant(0.15 / 3.0);
      for (int c = 0; c < 3; ++c) {
        if (mesh.faces[f](c) == seam.v0 || mesh.faces[f](c) == seam.v1) w(c) += 0.85 / 2.0;
      }
      side[k++] = sampleFace(model, f, w);
    }
    sum += (side[0] - side[1]).norm();
    ++count;
  }
  return count ? sum / count : 0.0;
}

}  // namespace

TEST(Texture, EveryFaceAViewSeesGetsAViewThatSeesItAndUnseenFacesAreReported) {
  // Terrain with a hill that hides part of the ground from the oblique cameras; the mesh
  // extends beyond what the cameras see.
  const synth::Height hill = [](double x, double y) {
    return 0.5 * std::exp(-((x - 0.2) * (x - 0.2) + y * y) / (2 * 0.12 * 0.12));
  };
  Scene scene;
  scene.mesh = synth::gridMesh(16, 1.6, hill);
  for (const Eigen::Vector3d& c :
       {Eigen::Vector3d(-1.0, -0.2, 1.6), Eigen::Vector3d(1.2, 0.3, 1.4),
        Eigen::Vector3d(0.0, -1.2, 1.5), Eigen::Vector3d(0.1, 1.0, 1.8)}) {
    scene.views.push_back(synth::lookAt(c, Eigen::Vector3d(0.1, 0, 0)));
    scene.images.push_back(synth::renderTruth(scene.mesh, scene.views.back()));
  }
  const TextureResult result = textureMesh(scene.mesh, scene.views, scene.loader(), quietOptions());
  size_t visible_somewhere = 0, labelled = 0, missed = 0, unseen = 0;
  for (size_t f = 0; f < scene.mesh.faces.size(); ++f) {
    bool any = false;
    for (size_t v = 0; v < scene.views.size(); ++v) any |= seesFace(scene.mesh, scene.views[v], f);
    visible_somewhere += any;
    const int label = result.labels[f];
    if (label == kNoLabel) {
      ++unseen;
      missed += any;
      continue;
    }
    ++labelled;
    EXPECT_TRUE(seesFace(scene.mesh, scene.views[label], static_cast<int>(f)))
        << "face " << f << " textured from view " << label << " that does not see it";
  }
  std::cout << labelled << " faces textured, " << unseen << " unseen (" << missed
            << " of them visible by the brute-force test), " << visible_somewhere
            << " visible somewhere" << std::endl;
  EXPECT_GT(unseen, 100u) << "the scene has faces outside every view";
  EXPECT_EQ(result.stats.faces_unseen, unseen);
  EXPECT_EQ(result.stats.faces_seen, labelled);
  // The sampled visibility test may refuse a face grazing a silhouette that the centroid ray
  // test accepts: at most 2 % of the visible faces.
  EXPECT_LE(missed, visible_somewhere / 50);
  // Some faces behind the hill are hidden from some view (occlusion is exercised).
  size_t hidden = 0;
  for (size_t f = 0; f < scene.mesh.faces.size(); ++f) {
    for (const auto& o : result.observations[f]) {
      hidden += !seesFace(scene.mesh, scene.views[o.view], static_cast<int>(f));
    }
  }
  EXPECT_EQ(hidden, 0u) << "observations of faces the brute-force test says are hidden";
}

TEST(Texture, MrfLabellingHasLowerEnergyAndFewerSeamsThanGreedy) {
  // Three nearly equivalent views and noisy images: the greedy pick flips between views from
  // face to face.
  Scene scene;
  scene.mesh = synth::gridMesh(12, 0.8, synth::flat);
  int seed = 1;
  for (const Eigen::Vector3d& c : {Eigen::Vector3d(-0.05, 0, 1.5), Eigen::Vector3d(0.05, 0.02, 1.5),
                                   Eigen::Vector3d(0.0, -0.05, 1.5)}) {
    scene.views.push_back(synth::lookAt(c, Eigen::Vector3d(0, 0, 0)));
    scene.images.push_back(
        synth::renderTruth(scene.mesh, scene.views.back(), 1.0, {}, 12.0, seed++));
  }
  TextureOptions options = quietOptions();
  const TextureResult mrf = textureMesh(scene.mesh, scene.views, scene.loader(), options);
  options.selection.use_mrf = false;
  const TextureResult greedy = textureMesh(scene.mesh, scene.views, scene.loader(), options);
  std::cout << "energy MRF " << mrf.stats.energy << " greedy " << greedy.stats.energy
            << ", seams MRF " << mrf.stats.seams << " greedy " << greedy.stats.seams
            << ", patches MRF " << mrf.stats.atlas.patches << " greedy "
            << greedy.stats.atlas.patches << std::endl;
  EXPECT_EQ(mrf.stats.greedy_energy, greedy.stats.energy);
  EXPECT_LT(mrf.stats.energy, 0.8 * greedy.stats.energy);
  EXPECT_LT(mrf.stats.seams * 4, greedy.stats.seams);
  EXPECT_LT(mrf.stats.atlas.patches * 4, greedy.stats.atlas.patches);
}

TEST(Texture, PhotoConsistencyRejectsTheViewThatSeesAFish) {
  // View 0 is the closest and most frontal (the data term prefers it) but a striped fish swims
  // between it and the sea floor; the other views see the floor.
  Scene scene;
  scene.mesh = synth::gridMesh(12, 0.8, synth::flat);
  const synth::Sphere fish{Eigen::Vector3d(0.1, 0.05, 0.45), 0.12};
  scene.views.push_back(
      synth::lookAt(Eigen::Vector3d(0, 0, 1.2), Eigen::Vector3d(0, 0, 0), 200, 160, 150));
  scene.images.push_back(synth::renderTruth(scene.mesh, scene.views.back(), 1.0, {fish}));
  for (const Eigen::Vector3d& c :
       {Eigen::Vector3d(-0.5, 0.3, 1.9), Eigen::Vector3d(0.5, 0.3, 1.9),
        Eigen::Vector3d(0.0, -0.6, 1.9), Eigen::Vector3d(0.3, 0.6, 2.0)}) {
    scene.views.push_back(synth::lookAt(c, Eigen::Vector3d(0, 0, 0)));
    scene.images.push_back(synth::renderTruth(scene.mesh, scene.views.back()));
  }
  // Faces behind the fish in view 0: their centroid's ray from view 0 meets the sphere.
  std::vector<int> behind_fish;
  const Eigen::Vector3d eye = scene.views[0].center();
  for (size_t f = 0; f < scene.mesh.faces.size(); ++f) {
    const auto& t = scene.mesh.faces[f];
    const Eigen::Vector3d m =
        (scene.mesh.vertices[t(0)] + scene.mesh.vertices[t(1)] + scene.mesh.vertices[t(2)]) / 3.0;
    const Eigen::Vector3d d = (m - eye).normalized();
    const double along = (fish.center - eye).dot(d);
    if ((eye + along * d - fish.center).norm() < fish.radius - 0.01) behind_fish.push_back(f);
  }
  ASSERT_GT(behind_fish.size(), 20u);

  TextureOptions options = quietOptions();
  options.selection.photo_consistency = false;
  const TextureResult fooled = textureMesh(scene.mesh, scene.views, scene.loader(), options);
  options.selection.photo_consistency = true;
  const TextureResult checked = textureMesh(scene.mesh, scene.views, scene.loader(), options);
  size_t fooled_count = 0, checked_count = 0, still_observed = 0;
  for (int f : behind_fish) {
    fooled_count += fooled.labels[f] == 0;
    checked_count += checked.labels[f] == 0;
    for (const auto& o : checked.observations[f]) still_observed += o.view == 0;
  }
  std::cout << behind_fish.size() << " faces behind the fish: textured from the fish's view "
            << fooled_count << " without, " << checked_count << " with the photo-consistency "
            << "check; " << checked.stats.rejected_observations << " observations rejected"
            << std::endl;
  EXPECT_GT(fooled_count, behind_fish.size() / 2) << "the scene must tempt the selection";
  EXPECT_EQ(checked_count, 0u);
  EXPECT_LE(still_observed, behind_fish.size() / 20);
  // Faces the fish does not hide keep view 0 (the check does not reject good views).
  size_t kept_elsewhere = 0, seen_elsewhere = 0;
  for (size_t f = 0; f < scene.mesh.faces.size(); ++f) {
    if (std::find(behind_fish.begin(), behind_fish.end(), f) != behind_fish.end()) continue;
    if (fooled.labels[f] != 0) continue;
    ++seen_elsewhere;
    kept_elsewhere += checked.labels[f] == 0;
  }
  EXPECT_GT(kept_elsewhere, seen_elsewhere * 8 / 10);
  // The re-rendered model from view 0 shows the floor, not the fish.
  const cv::Mat3b truth = synth::renderTruth(scene.mesh, scene.views[0]);
  cv::Mat1b fish_mask(truth.size(), uint8_t{0});
  for (int y = 0; y < truth.rows; ++y) {
    for (int x = 0; x < truth.cols; ++x) {
      if (scene.images[0](y, x) != truth(y, x)) fish_mask(y, x) = 255;
    }
  }
  const double psnr_fooled =
      psnr(renderTexturedModel(fooled.model, scene.views[0]).image, truth, fish_mask);
  const double psnr_checked =
      psnr(renderTexturedModel(checked.model, scene.views[0]).image, truth, fish_mask);
  std::cout << "PSNR under the fish: " << psnr_fooled << " dB without, " << psnr_checked
            << " dB with the check" << std::endl;
  // Faces only partly behind the fish keep a few fish pixels (their mean colour passes).
  EXPECT_GT(psnr_checked, 20.0);
  EXPECT_GT(psnr_checked, psnr_fooled + 10.0);
}

TEST(Texture, SeamLevelingRemovesTheJumpBetweenViewsOfDifferentExposure) {
  // Two views, each closer to one half of the floor; the right one 35 % brighter.
  Scene scene;
  scene.mesh = synth::gridMesh(12, 0.8, synth::flat);
  scene.views.push_back(synth::lookAt(Eigen::Vector3d(-0.45, 0, 1.3), Eigen::Vector3d(-0.3, 0, 0)));
  scene.images.push_back(synth::renderTruth(scene.mesh, scene.views.back(), 1.0));
  scene.views.push_back(synth::lookAt(Eigen::Vector3d(0.45, 0, 1.3), Eigen::Vector3d(0.3, 0, 0)));
  scene.images.push_back(synth::renderTruth(scene.mesh, scene.views.back(), 1.35));
  TextureOptions options = quietOptions();
  options.global_leveling = false;
  options.atlas.local_blending = false;
  const TextureResult raw = textureMesh(scene.mesh, scene.views, scene.loader(), options);
  options.global_leveling = true;
  const TextureResult leveled = textureMesh(scene.mesh, scene.views, scene.loader(), options);
  options.atlas.local_blending = true;
  const TextureResult both = textureMesh(scene.mesh, scene.views, scene.loader(), options);
  options.global_leveling = false;
  const TextureResult blended = textureMesh(scene.mesh, scene.views, scene.loader(), options);
  ASSERT_GT(raw.stats.seams, 5u);
  ASSERT_EQ(raw.labels, leveled.labels);
  const double jump_raw = meanSeamJump(raw.model, scene.mesh, raw.labels);
  const double jump_leveled = meanSeamJump(leveled.model, scene.mesh, leveled.labels);
  const double jump_both = meanSeamJump(both.model, scene.mesh, both.labels);
  const double jump_blended = meanSeamJump(blended.model, scene.mesh, blended.labels);
  std::cout << "mean colour jump across " << raw.stats.seams << " seam edges: raw " << jump_raw
            << ", levelled " << jump_leveled << ", blended " << jump_blended << ", both "
            << jump_both << "; levelling terms " << leveled.stats.leveling.mean_jump_before
            << " -> " << leveled.stats.leveling.mean_jump_after << std::endl;
  EXPECT_GT(jump_raw, 25.0);  // 35 % of ~130 grey levels
  EXPECT_LT(jump_leveled, 0.3 * jump_raw);
  EXPECT_LT(jump_blended, 0.6 * jump_raw);
  EXPECT_LT(jump_both, 0.25 * jump_raw);
  EXPECT_LT(leveled.stats.leveling.mean_jump_after, 0.2 * leveled.stats.leveling.mean_jump_before);
}

TEST(Texture, ObjLoadsBackInOpen3DAndRendersLikeTheModel) {
  Scene scene;
  scene.mesh = synth::gridMesh(8, 0.8, synth::flat);
  for (const Eigen::Vector3d& c : {Eigen::Vector3d(-0.4, 0, 1.4), Eigen::Vector3d(0.4, 0.1, 1.4),
                                   Eigen::Vector3d(0, -0.5, 1.5)}) {
    scene.views.push_back(synth::lookAt(c, Eigen::Vector3d(0, 0, 0)));
    scene.images.push_back(synth::renderTruth(scene.mesh, scene.views.back()));
  }
  const TextureResult result = textureMesh(scene.mesh, scene.views, scene.loader(), quietOptions());
  TempDir dir;
  writeObj(result.model, dir.path, "model");
  ASSERT_TRUE(fs::exists(dir.path / "model.obj"));
  ASSERT_TRUE(fs::exists(dir.path / "model.mtl"));
  ASSERT_TRUE(fs::exists(dir.path / "model_0.png"));

  open3d::geometry::TriangleMesh loaded;
  ASSERT_TRUE(open3d::io::ReadTriangleMesh((dir.path / "model.obj").string(), loaded));
  EXPECT_EQ(loaded.triangles_.size(), scene.mesh.faces.size());
  EXPECT_EQ(loaded.triangle_uvs_.size(), 3 * scene.mesh.faces.size());
  // Open3D keeps an empty texture for its default material at index 0.
  size_t textures = 0;
  for (const auto& texture : loaded.textures_) textures += !texture.IsEmpty();
  EXPECT_EQ(textures, result.model.pages.size());
  for (int id : loaded.triangle_material_ids_) {
    ASSERT_GE(id, 0);
    ASSERT_LT(static_cast<size_t>(id), loaded.textures_.size());
    EXPECT_FALSE(loaded.textures_[id].IsEmpty());
  }
  for (const auto& uv : loaded.triangle_uvs_) {
    EXPECT_GE(uv.minCoeff(), 0.0);
    EXPECT_LE(uv.maxCoeff(), 1.0);
  }

  const TexturedModel back = readObj(dir.path / "model.obj");
  EXPECT_EQ(back.faces.size(), result.model.faces.size());
  EXPECT_EQ(back.pages.size(), result.model.pages.size());
  const ViewGeometry check =
      synth::lookAt(Eigen::Vector3d(0.1, 0.1, 1.6), Eigen::Vector3d(0, 0, 0));
  const Rendering a = renderTexturedModel(result.model, check);
  const Rendering b = renderTexturedModel(back, check);
  EXPECT_GT(cv::countNonZero(a.mask), a.mask.total() / 2);
  EXPECT_GT(psnr(a.image, b.image, a.mask), 45.0);  // float UVs in text: sub-texel differences

  // Bad files: named in the error.
  std::ofstream(dir.path / "broken.obj")
      << "mtllib model.mtl\nv 0 0 0\nusemtl page_0\nf 1/1 2/2 3/3\n";
  try {
    readObj(dir.path / "broken.obj");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("broken.obj:4"), std::string::npos) << e.what();
  }
}

TEST(Texture, RenderedHeldOutViewMatchesTheTrueTexture) {
  // Gentle terrain, five survey views; a sixth view is held out and rendered from the model.
  const synth::Height terrain = [](double x, double y) {
    return 0.08 * std::sin(2 * x) * std::cos(2 * y);
  };
  Scene scene;
  scene.mesh = synth::gridMesh(16, 1.0, terrain);
  for (const Eigen::Vector3d& c : {Eigen::Vector3d(-0.5, -0.4, 1.3),
                                   Eigen::Vector3d(0.5, -0.4, 1.3), Eigen::Vector3d(-0.5, 0.4, 1.3),
                                   Eigen::Vector3d(0.5, 0.4, 1.3), Eigen::Vector3d(0, 0, 1.6)}) {
    scene.views.push_back(
        synth::lookAt(c, Eigen::Vector3d(c.x() * 0.6, c.y() * 0.6, 0), 200, 150, 160));
    scene.images.push_back(synth::renderTruth(scene.mesh, scene.views.back()));
  }
  const TextureResult result = textureMesh(scene.mesh, scene.views, scene.loader(), quietOptions());
  const ViewGeometry held_out =
      synth::lookAt(Eigen::Vector3d(0.2, -0.1, 1.1), Eigen::Vector3d(0.1, 0.0, 0), 200, 150, 160);
  const cv::Mat3b truth = synth::renderTruth(scene.mesh, held_out);
  const Rendering rendering = renderTexturedModel(result.model, held_out);
  // Compare where the model is textured from some view (unseen faces are flat grey).
  cv::Mat1b mask = rendering.mask.clone();
  const RasterBuffers buffers = rasterize(scene.mesh.vertices, scene.mesh.faces, held_out);
  for (int y = 0; y < mask.rows; ++y) {
    for (int x = 0; x < mask.cols; ++x) {
      const int f = buffers.face(y, x);
      if (f < 0 || result.labels[f] == kNoLabel) mask(y, x) = 0;
    }
  }
  ASSERT_GT(cv::countNonZero(mask), static_cast<int>(mask.total() * 0.8));
  const double value = psnr(rendering.image, truth, mask);
  std::cout << "held-out view PSNR " << value << " dB over " << cv::countNonZero(mask) << " px"
            << std::endl;
  EXPECT_GT(value, 30.0);
}

TEST(Texture, RendererDrawsTheTexelsOfAHandMadeModel) {
  // One square facing the camera, its page split into four coloured quadrants.
  TexturedModel model;
  model.vertices = {{-1, -1, 5}, {1, -1, 5}, {1, 1, 5}, {-1, 1, 5}};
  model.faces = {{0, 1, 2}, {0, 2, 3}};
  // World y down the image: vertex (-1,-1) is the top-left pixel, texture (0, 1) in OBJ's v-up.
  auto uv = [](const Eigen::Vector3d& v) {
    return Eigen::Vector2f(static_cast<float>((v.x() + 1) / 2),
                           static_cast<float>(1 - (v.y() + 1) / 2));
  };
  for (const auto& f : model.faces) {
    model.face_uvs.push_back(
        {uv(model.vertices[f(0)]), uv(model.vertices[f(1)]), uv(model.vertices[f(2)])});
  }
  model.face_page = {0, 0};
  cv::Mat3b page(64, 64);
  page(cv::Rect(0, 0, 32, 32)).setTo(cv::Vec3b(255, 0, 0));
  page(cv::Rect(32, 0, 32, 32)).setTo(cv::Vec3b(0, 255, 0));
  page(cv::Rect(0, 32, 32, 32)).setTo(cv::Vec3b(0, 0, 255));
  page(cv::Rect(32, 32, 32, 32)).setTo(cv::Vec3b(255, 255, 255));
  model.pages = {page};
  ViewGeometry view;
  view.camera = scene::Camera::pinhole(1, 101, 101, 100, 100, 50, 50);
  const Rendering r = renderTexturedModel(model, view, cv::Vec3b(7, 7, 7));
  EXPECT_EQ(r.image(30, 30), cv::Vec3b(255, 0, 0));      // top-left
  EXPECT_EQ(r.image(30, 70), cv::Vec3b(0, 255, 0));      // top-right
  EXPECT_EQ(r.image(70, 30), cv::Vec3b(0, 0, 255));      // bottom-left
  EXPECT_EQ(r.image(70, 70), cv::Vec3b(255, 255, 255));  // bottom-right
  EXPECT_EQ(r.image(5, 5), cv::Vec3b(7, 7, 7));          // the square covers +-20 px
  EXPECT_EQ(r.mask(5, 5), 0);
  EXPECT_NEAR(r.depth(50, 50), 5.0, 1e-5);
}

TEST(Texture, NoObservedFaceOrEmptyMeshStopsWithTheCause) {
  Scene scene;
  scene.mesh = synth::gridMesh(4, 0.5, synth::flat);
  // Cameras looking up, away from the floor.
  scene.views.push_back(synth::lookAt(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 0, 3)));
  scene.images.push_back(cv::Mat3b(120, 160, cv::Vec3b(1, 2, 3)));
  try {
    textureMesh(scene.mesh, scene.views, scene.loader(), quietOptions());
    FAIL() << "a mesh no view sees was textured";
  } catch (const StageError& e) {
    EXPECT_EQ(e.stage(), "texture");
    EXPECT_NE(std::string(e.what()).find("no face"), std::string::npos) << e.what();
  }
  FaceMesh empty;
  EXPECT_THROW(textureMesh(empty, scene.views, scene.loader(), quietOptions()), StageError);
  EXPECT_THROW(textureMesh(scene.mesh, {}, scene.loader(), quietOptions()), StageError);
}

TEST(Texture, OptionsRejectBadValuesNamingTheField) {
  TextureOptions options;
  options.selection.smoothness = -1;
  try {
    options.check();
    FAIL();
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("smoothness = -1"), std::string::npos) << e.what();
  }
  options = TextureOptions();
  options.selection.data_term = "sharpest";
  EXPECT_THROW(options.check(), OptionError);
  options = TextureOptions();
  options.selection.photo_consistency_min_views = 2;
  EXPECT_THROW(options.check(), OptionError);
  options = TextureOptions();
  options.atlas.max_page_size = 10;
  EXPECT_THROW(options.check(), OptionError);
  options = TextureOptions();
  options.leveling.regularization = 0;
  EXPECT_THROW(options.check(), OptionError);
  EXPECT_NO_THROW(TextureOptions().check());
}

TEST(Texture, PhotoConsistencyKeepsViewsThatDifferOnlyInExposure) {
  // Three views of the floor, two alike and one 35 % brighter, with noise, no occluder: a
  // fixed colour bandwidth would take the bright view for an occluder everywhere; the gains
  // are estimated and divided out before the mean-shift, so nothing is rejected.
  Scene scene;
  scene.mesh = synth::gridMesh(10, 0.8, synth::flat);
  const double gains[] = {0.85, 0.86, 1.15};
  int v = 0;
  for (const Eigen::Vector3d& c :
       {Eigen::Vector3d(-0.2, -0.2, 1.6), Eigen::Vector3d(0.2, -0.2, 1.6),
        Eigen::Vector3d(0, 0.25, 1.7)}) {
    scene.views.push_back(synth::lookAt(c, Eigen::Vector3d(0, 0, 0), 160, 120, 100));
    scene.images.push_back(
        synth::renderTruth(scene.mesh, scene.views.back(), gains[v], {}, 2.0, v + 1));
    ++v;
  }
  ViewSelectionOptions options;
  auto observations = observeFaces(scene.mesh, scene.views, scene.loader(), options);
  size_t total = 0, faces_with_three = 0;
  for (const auto& face : observations) {
    total += face.size();
    faces_with_three += face.size() >= 3;
  }
  ASSERT_GT(faces_with_three, scene.mesh.faces.size() / 2);
  EXPECT_EQ(rejectInconsistentViews(observations, options), 0u) << "of " << total;
}

TEST(Texture, AtlasStaysWithinItsTexelBudget) {
  Scene scene;
  scene.mesh = synth::gridMesh(10, 0.8, synth::flat);
  for (const Eigen::Vector3d& c : {Eigen::Vector3d(-0.3, 0, 1.0), Eigen::Vector3d(0.3, 0, 1.0)}) {
    scene.views.push_back(synth::lookAt(c, Eigen::Vector3d(c.x(), 0, 0), 320, 240, 300));
    scene.images.push_back(synth::renderTruth(scene.mesh, scene.views.back()));
  }
  TextureOptions options = quietOptions();
  const TextureResult native = textureMesh(scene.mesh, scene.views, scene.loader(), options);
  const double native_texels = native.stats.atlas.fill_ratio * native.stats.atlas.pages *
                               native.stats.atlas.page_size * native.stats.atlas.page_size;
  options.atlas.max_atlas_megapixels = native_texels / 4e6;  // a quarter of what it needs
  const TextureResult budget = textureMesh(scene.mesh, scene.views, scene.loader(), options);
  const double texels = budget.stats.atlas.fill_ratio * budget.stats.atlas.pages *
                        budget.stats.atlas.page_size * budget.stats.atlas.page_size;
  std::cout << "native " << native_texels << " texels (scale " << native.stats.atlas.texel_scale
            << "), budget " << options.atlas.max_atlas_megapixels * 1e6 << ": " << texels
            << " texels (scale " << budget.stats.atlas.texel_scale << ")" << std::endl;
  EXPECT_EQ(native.stats.atlas.texel_scale, 1.0);
  EXPECT_LT(budget.stats.atlas.texel_scale, 0.6);
  EXPECT_LE(texels, 1.05 * options.atlas.max_atlas_megapixels * 1e6);
  // Still the right texture, at half the resolution (a view inside what the survey saw).
  const ViewGeometry check = synth::lookAt(Eigen::Vector3d(0, 0, 0.7), Eigen::Vector3d(0, 0, 0));
  const Rendering rendering = renderTexturedModel(budget.model, check);
  const Rendering full = renderTexturedModel(native.model, check);
  const cv::Mat3b truth = synth::renderTruth(scene.mesh, check);
  const double psnr_native = psnr(full.image, truth, full.mask);
  const double psnr_budget = psnr(rendering.image, truth, rendering.mask);
  std::cout << "PSNR native " << psnr_native << " dB, at half resolution " << psnr_budget << " dB"
            << std::endl;
  EXPECT_GT(psnr_native, 45.0);
  EXPECT_GT(psnr_budget, 40.0);
}
