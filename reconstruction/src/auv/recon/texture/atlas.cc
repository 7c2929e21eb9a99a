#include "auv/recon/texture/atlas.h"

#include <stb/stb_rect_pack.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>

#include "auv/recon/common/stage_error.h"

namespace auv::recon::texture {

void AtlasOptions::check() const {
  AUV_RECON_CHECK_OPTION(max_page_size >= 64 && max_page_size <= 16384, max_page_size,
                         "must be in [64, 16384]");
  AUV_RECON_CHECK_OPTION(padding >= 1 && padding <= 16, padding, "must be in [1, 16]");
  AUV_RECON_CHECK_OPTION(blend_width >= 1 && blend_width <= 64, blend_width, "must be in [1, 64]");
  AUV_RECON_CHECK_OPTION(max_atlas_megapixels > 0, max_atlas_megapixels, "must be > 0");
  AUV_RECON_CHECK_OPTION(unseen_gray >= 0 && unseen_gray <= 255, unseen_gray,
                         "must be in [0, 255]");
}

namespace {

int findRoot(std::vector<int>& parent, int x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}

struct Patch {
  int label = kNoLabel;  ///< kNoLabel: the block of unseen faces
  std::vector<int> faces;
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  ///< source pixel at the first texel
  double scale = 1.0;                                ///< texels per source pixel
  int width = 0, height = 0;                         ///< texels, padding included
  int page = -1, x = 0, y = 0;                       ///< placement in the atlas
};

/// Distance from p to the segment ab and the parameter of the closest point.
double segmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                       double& t) {
  const Eigen::Vector2d ab = b - a;
  const double length2 = ab.squaredNorm();
  t = length2 > 0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

bool observes(const std::vector<FaceObservation>& observations, int view) {
  return std::any_of(observations.begin(), observations.end(),
                     [&](const FaceObservation& o) { return o.view == view; });
}

}  // namespace

std::pair<std::vector<int>, int> findPatches(const FaceMesh& mesh, const std::vector<int>& labels) {
  std::vector<int> parent(mesh.faces.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& [a, b] : mesh.faceAdjacency()) {
    if (labels[a] == kNoLabel || labels[a] != labels[b]) continue;
    parent[findRoot(parent, a)] = findRoot(parent, b);
  }
  std::vector<int> patch(mesh.faces.size(), -1);
  std::map<int, int> index_of_root;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (labels[f] == kNoLabel) continue;
    const int root = findRoot(parent, static_cast<int>(f));
    const auto [it, inserted] = index_of_root.emplace(root, static_cast<int>(index_of_root.size()));
    patch[f] = it->second;
  }
  return {patch, static_cast<int>(index_of_root.size())};
}

AtlasResult buildAtlas(const FaceMesh& mesh, const std::vector<ViewGeometry>& views,
                       const std::vector<int>& labels,
                       const std::vector<std::vector<FaceObservation>>& observations,
                       const ColorOffsets& offsets, const ImageLoader& images,
                       const AtlasOptions& options) {
  options.check();
  AtlasResult result;
  const int pad = options.padding;

  // Patches and their rectangles.
  const auto [patch_of_face, num_patches] = findPatches(mesh, labels);
  std::vector<Patch> patches(num_patches);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (patch_of_face[f] < 0) continue;
    Patch& patch = patches[patch_of_face[f]];
    patch.label = labels[f];
    patch.faces.push_back(static_cast<int>(f));
  }
  const int max_content = options.max_page_size - 2 * pad - 2;
  std::vector<Eigen::Vector2d> patch_extent;  // source pixels
  for (Patch& patch : patches) {
    const ViewGeometry& view = views[patch.label];
    Eigen::Vector2d low = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector2d high = -low;
    for (int f : patch.faces) {
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector2d p = view.project(view.toCamera(mesh.vertices[mesh.faces[f](k)]));
        low = low.cwiseMin(p);
        high = high.cwiseMax(p);
      }
    }
    patch.origin = low.array().floor().matrix();
    patch_extent.push_back(high - patch.origin);
  }
  // Texel budget: patches at native resolution unless their total exceeds it (hundreds of
  // overlapping full-resolution views); then every patch is scaled by the same factor.
  double native_area = 0;
  for (const Eigen::Vector2d& extent : patch_extent) {
    native_area += (extent.x() + 1 + 2 * pad) * (extent.y() + 1 + 2 * pad);
  }
  const double budget = options.max_atlas_megapixels * 1e6;
  result.stats.texel_scale = native_area > budget ? std::sqrt(budget / native_area) : 1.0;
  for (size_t p = 0; p < patches.size(); ++p) {
    Patch& patch = patches[p];
    const Eigen::Vector2d& extent = patch_extent[p];
    patch.scale =
        std::min(result.stats.texel_scale, max_content / std::max(1.0, extent.maxCoeff()));
    patch.width = static_cast<int>(std::ceil(extent.x() * patch.scale)) + 1 + 2 * pad;
    patch.height = static_cast<int>(std::ceil(extent.y() * patch.scale)) + 1 + 2 * pad;
  }
  std::vector<int> unseen;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (labels[f] == kNoLabel) unseen.push_back(static_cast<int>(f));
  }
  if (!unseen.empty()) {
    Patch block;
    block.faces = unseen;
    block.width = block.height = 2 + 2 * pad;
    patches.push_back(block);
  }
  if (patches.empty()) throw StageError("texture", "the mesh has no faces to texture");

  // Packing: square pages just large enough for everything (power of two), more pages when
  // it does not fit in the largest one.
  double area = 0;
  int largest = 0;
  for (const Patch& patch : patches) {
    area += static_cast<double>(patch.width) * patch.height;
    largest = std::max({largest, patch.width, patch.height});
  }
  int page_size = 64;
  while (page_size < options.max_page_size &&
         (page_size < largest || static_cast<double>(page_size) * page_size < 1.2 * area)) {
    page_size *= 2;
  }
  page_size = std::min(page_size, options.max_page_size);
  std::vector<int> remaining(patches.size());
  std::iota(remaining.begin(), remaining.end(), 0);
  int pages = 0;
  while (!remaining.empty()) {
    std::vector<stbrp_rect> rects(remaining.size());
    for (size_t i = 0; i < remaining.size(); ++i) {
      rects[i].id = remaining[i];
      rects[i].w = patches[remaining[i]].width;
      rects[i].h = patches[remaining[i]].height;
    }
    stbrp_context context;
    std::vector<stbrp_node> nodes(page_size);
    stbrp_init_target(&context, page_size, page_size, nodes.data(), page_size);
    stbrp_pack_rects(&context, rects.data(), static_cast<int>(rects.size()));
    std::vector<int> left;
    for (const stbrp_rect& rect : rects) {
      if (rect.was_packed) {
        Patch& patch = patches[rect.id];
        patch.page = pages;
        patch.x = rect.x;
        patch.y = rect.y;
      } else {
        left.push_back(rect.id);
      }
    }
    if (left.size() == remaining.size()) {
      throw StageError("texture", "atlas packing: a patch does not fit a " +
                                      std::to_string(page_size) + " px page");
    }
    remaining = std::move(left);
    ++pages;
  }

  TexturedModel& model = result.model;
  model.vertices = mesh.vertices;
  model.faces = mesh.faces;
  model.face_uvs.resize(mesh.faces.size());
  model.face_page.assign(mesh.faces.size(), 0);
  model.pages.assign(pages, cv::Mat3b());
  for (auto& page : model.pages) page = cv::Mat3b(page_size, page_size, cv::Vec3b(0, 0, 0));
  auto uvOf = [&](const Eigen::Vector2d& texel) {
    return Eigen::Vector2f(static_cast<float>((texel.x() + 0.5) / page_size),
                           static_cast<float>(1.0 - (texel.y() + 0.5) / page_size));
  };

  // Seam edges per patch (the patch's own side), for the blending.
  const std::vector<SeamEdge> seams =
      options.local_blending ? findSeamEdges(mesh, labels) : std::vector<SeamEdge>();
  std::vector<std::vector<std::pair<int, int>>> seams_of_patch(patches.size());  // (seam, face)
  for (size_t s = 0; s < seams.size(); ++s) {
    seams_of_patch[patch_of_face[seams[s].face_a]].emplace_back(static_cast<int>(s),
                                                                seams[s].face_a);
    seams_of_patch[patch_of_face[seams[s].face_b]].emplace_back(static_cast<int>(s),
                                                                seams[s].face_b);
  }

  // Patches of one label share the label's image: one task per label.
  std::map<int, std::vector<int>> patches_of_label;
  for (size_t p = 0; p < patches.size(); ++p) patches_of_label[patches[p].label].push_back(p);
  std::vector<std::pair<int, std::vector<int>>> tasks(patches_of_label.begin(),
                                                      patches_of_label.end());
  size_t blended = 0, texels = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : blended, texels)
  for (size_t task = 0; task < tasks.size(); ++task) {
    const int label = tasks[task].first;
    if (label == kNoLabel) {  // the unseen block: one flat colour
      const Patch& block = patches[tasks[task].second.front()];
      const cv::Rect rect(block.x, block.y, block.width, block.height);
      model.pages[block.page](rect).setTo(
          cv::Vec3b(options.unseen_gray, options.unseen_gray, options.unseen_gray));
      const Eigen::Vector2d center(block.x + 0.5 * (block.width - 1),
                                   block.y + 0.5 * (block.height - 1));
      for (int f : block.faces) {
        model.face_uvs[f] = {uvOf(center), uvOf(center), uvOf(center)};
        model.face_page[f] = block.page;
      }
      continue;
    }
    const ViewGeometry& view = views[label];
    const cv::Mat3b image = images(label);
    for (int p : tasks[task].second) {
      const Patch& patch = patches[p];
      cv::Mat3b& page = model.pages[patch.page];
      const Eigen::Vector2d corner(patch.x + pad, patch.y + pad);
      auto texelOf = [&](const Eigen::Vector2d& pixel) {
        return Eigen::Vector2d(corner + (pixel - patch.origin) * patch.scale);
      };
      // Nearest seam within blend_width of each texel of the patch (local coordinates).
      cv::Mat1f seam_distance(patch.height, patch.width, std::numeric_limits<float>::infinity());
      cv::Mat1i seam_index(patch.height, patch.width, -1);
      cv::Mat1f seam_t(patch.height, patch.width, 0.0f);
      for (const auto& [s, face] : seams_of_patch[p]) {
        const SeamEdge& seam = seams[s];
        const Eigen::Vector2d a = texelOf(view.project(view.toCamera(mesh.vertices[seam.v0]))) -
                                  Eigen::Vector2d(patch.x, patch.y);
        const Eigen::Vector2d b = texelOf(view.project(view.toCamera(mesh.vertices[seam.v1]))) -
                                  Eigen::Vector2d(patch.x, patch.y);
        const int w = options.blend_width;
        const int x0 = std::max(0, static_cast<int>(std::floor(std::min(a.x(), b.x()))) - w);
        const int x1 =
            std::min(patch.width - 1, static_cast<int>(std::ceil(std::max(a.x(), b.x()))) + w);
        const int y0 = std::max(0, static_cast<int>(std::floor(std::min(a.y(), b.y()))) - w);
        const int y1 =
            std::min(patch.height - 1, static_cast<int>(std::ceil(std::max(a.y(), b.y()))) + w);
        for (int y = y0; y <= y1; ++y) {
          for (int x = x0; x <= x1; ++x) {
            double t;
            const double d = segmentDistance(Eigen::Vector2d(x, y), a, b, t);
            if (d < seam_distance(y, x)) {
              seam_distance(y, x) = static_cast<float>(d);
              seam_index(y, x) = s;
              seam_t(y, x) = static_cast<float>(t);
            }
          }
        }
      }
      // The images on the other side of this patch's seams, loaded once.
      std::map<int, cv::Mat3b> other_images;
      for (const auto& [s, face] : seams_of_patch[p]) {
        const int other = seams[s].label_a == label ? seams[s].label_b : seams[s].label_a;
        if (!other_images.count(other)) other_images[other] = images(other);
      }
      cv::Mat1f owner(patch.height, patch.width, std::numeric_limits<float>::infinity());
      for (int f : patch.faces) {
        const Eigen::Vector3i& face = mesh.faces[f];
        Eigen::Vector2d tex[3];
        double depth[3];
        for (int k = 0; k < 3; ++k) {
          const Eigen::Vector3d c = view.toCamera(mesh.vertices[face(k)]);
          depth[k] = c.z();
          tex[k] = texelOf(view.project(c));
          model.face_uvs[f][k] = uvOf(tex[k]);
        }
        model.face_page[f] = patch.page;
        const Eigen::Vector3f g[3] = {offsets.at(face(0), label), offsets.at(face(1), label),
                                      offsets.at(face(2), label)};
        const int x0 = std::max(
            patch.x,
            static_cast<int>(std::floor(std::min({tex[0].x(), tex[1].x(), tex[2].x()}))) - pad);
        const int x1 = std::min(
            patch.x + patch.width - 1,
            static_cast<int>(std::ceil(std::max({tex[0].x(), tex[1].x(), tex[2].x()}))) + pad);
        const int y0 = std::max(
            patch.y,
            static_cast<int>(std::floor(std::min({tex[0].y(), tex[1].y(), tex[2].y()}))) - pad);
        const int y1 = std::min(
            patch.y + patch.height - 1,
            static_cast<int>(std::ceil(std::max({tex[0].y(), tex[1].y(), tex[2].y()}))) + pad);
        for (int y = y0; y <= y1; ++y) {
          for (int x = x0; x <= x1; ++x) {
            const Eigen::Vector2d texel(x, y);
            Eigen::Vector3d w;
            if (!barycentric2d(tex[0], tex[1], tex[2], texel, w)) continue;
            double distance = 0;
            if (w.minCoeff() < 0) {
              double t;
              distance = std::min({segmentDistance(texel, tex[0], tex[1], t),
                                   segmentDistance(texel, tex[1], tex[2], t),
                                   segmentDistance(texel, tex[2], tex[0], t)});
              if (distance > pad + 0.5) continue;
              w = w.cwiseMax(0.0);
              w /= w.sum();
            }
            float& best = owner(y - patch.y, x - patch.x);
            if (distance >= best) continue;
            best = static_cast<float>(distance);
            const Eigen::Vector2d source = patch.origin + (texel - corner) / patch.scale;
            Eigen::Vector3f color =
                sampleBilinear(image, source.x(), source.y()) + static_cast<float>(w(0)) * g[0] +
                static_cast<float>(w(1)) * g[1] + static_cast<float>(w(2)) * g[2];
            // Local blending towards the other side of the nearest seam.
            const int s = seam_index(y - patch.y, x - patch.x);
            const float d = seam_distance(y - patch.y, x - patch.x);
            if (s >= 0 && d < options.blend_width) {
              const SeamEdge& seam = seams[s];
              const int other = seam.label_a == label ? seam.label_b : seam.label_a;
              if (observes(observations[f], other)) {
                // The surface point of this texel (perspective-correct weights).
                Eigen::Vector3d wp(w(0) / depth[0], w(1) / depth[1], w(2) / depth[2]);
                wp /= wp.sum();
                const Eigen::Vector3d point = wp(0) * mesh.vertices[face(0)] +
                                              wp(1) * mesh.vertices[face(1)] +
                                              wp(2) * mesh.vertices[face(2)];
                const Eigen::Vector3d c = views[other].toCamera(point);
                const cv::Mat3b& other_image = other_images[other];
                if (c.z() > 0 && !other_image.empty()) {
                  const Eigen::Vector2d q = views[other].project(c);
                  if (q.x() >= 0 && q.y() >= 0 && q.x() <= other_image.cols - 1 &&
                      q.y() <= other_image.rows - 1) {
                    const float t = seam_t(y - patch.y, x - patch.x);
                    const Eigen::Vector3f other_color = sampleBilinear(other_image, q.x(), q.y()) +
                                                        (1 - t) * offsets.at(seam.v0, other) +
                                                        t * offsets.at(seam.v1, other);
                    const float alpha = 0.5f * (1.0f - d / options.blend_width);
                    color = (1 - alpha) * color + alpha * other_color;
                    ++blended;
                  }
                }
              }
            }
            page(y, x) = cv::Vec3b(cv::saturate_cast<uint8_t>(color(0)),
                                   cv::saturate_cast<uint8_t>(color(1)),
                                   cv::saturate_cast<uint8_t>(color(2)));
          }
        }
      }
      texels +=
          static_cast<size_t>(cv::countNonZero(owner < std::numeric_limits<float>::infinity()));
    }
  }
  result.stats.patches = static_cast<size_t>(num_patches);
  result.stats.pages = static_cast<size_t>(pages);
  result.stats.page_size = page_size;
  result.stats.unseen_faces = unseen.size();
  result.stats.blended_texels = blended;
  result.stats.fill_ratio =
      static_cast<double>(texels) / (static_cast<double>(page_size) * page_size * pages);
  return result;
}

}  // namespace auv::recon::texture
