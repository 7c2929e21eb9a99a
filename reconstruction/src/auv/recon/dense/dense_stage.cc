#include "auv/recon/dense/dense_stage.h"

#include <chrono>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <list>
#include <sstream>
#include <unordered_map>

#include <opencv2/imgproc.hpp>

#include "auv/recon/common/option_set.h"
#include "auv/recon/common/progress.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/dense/depth_map.h"
#include "auv/recon/dense/memory.h"
#include "auv/recon/masks/mask.h"
#include "auv/recon/scene/colmap_text.h"
#include "auv/recon/scene/ply.h"

namespace fs = std::filesystem;

namespace auv::recon::dense {

namespace {
constexpr const char* kStage = "dense";
using Clock = std::chrono::steady_clock;

/// A few loaded items by image id, least recently used dropped first.
template <class T>
class LruCache {
 public:
  explicit LruCache(size_t capacity) : capacity_(std::max<size_t>(capacity, 1)) {}
  template <class Load>
  T& get(uint32_t id, const Load& load) {
    const auto found = index_.find(id);
    if (found != index_.end()) {
      order_.splice(order_.begin(), order_, found->second);
      return found->second->second;
    }
    order_.emplace_front(id, load());
    index_[id] = order_.begin();
    if (order_.size() > capacity_) {
      index_.erase(order_.back().first);
      order_.pop_back();
    }
    return order_.front().second;
  }

 private:
  size_t capacity_;
  std::list<std::pair<uint32_t, T>> order_;
  std::unordered_map<uint32_t, typename std::list<std::pair<uint32_t, T>>::iterator> index_;
};

/// Starts a sub-stage's time and peak memory.
class SubStage {
 public:
  explicit SubStage(SubStageFigures& figures)
      : figures_(figures), start_(Clock::now()), cpu_start_(std::clock()) {
    resetPeakMemory();
  }
  ~SubStage() {
    figures_.seconds = std::chrono::duration<double>(Clock::now() - start_).count();
    figures_.cpu_seconds = static_cast<double>(std::clock() - cpu_start_) / CLOCKS_PER_SEC;
    figures_.peak_memory_bytes = peakMemoryBytes();
  }

 private:
  SubStageFigures& figures_;
  Clock::time_point start_;
  std::clock_t cpu_start_;
};

fs::path depthMapPath(const fs::path& folder, const std::string& image_name) {
  fs::path relative(image_name);
  relative.replace_extension(".depth.bin");
  return folder / "depth_maps" / relative;
}

nlohmann::json figures(const SubStageFigures& f) {
  return {{"seconds", f.seconds},
          {"cpu_seconds", f.cpu_seconds},
          {"peak_memory_mb", f.peak_memory_bytes / 1048576.0}};
}
}  // namespace

void DenseStageOptions::check() const {
  AUV_RECON_CHECK_OPTION(max_image_size == 0 || max_image_size >= 64, max_image_size,
                         "must be 0 (full size) or >= 64 px");
  AUV_RECON_CHECK_OPTION(min_registered_images >= 2, min_registered_images, "must be >= 2");
  AUV_RECON_CHECK_OPTION(min_points >= 0, min_points, "must be >= 0");
  AUV_RECON_CHECK_OPTION(image_cache >= 1, image_cache, "must be >= 1");
  neighbours.check();
  matcher.check();
  fusion.check();
}

void DenseStageOptions::bind(OptionSet& set) {
  set.add("max_image_size", &max_image_size,
          "px: longer side depth maps are computed at (0: full size)");
  set.add("min_registered_images", &min_registered_images,
          "fewer registered images in sparse/: error");
  set.add("min_points", &min_points, "a fused cloud with fewer points: error");
  set.add("image_cache", &image_cache, "images kept in memory between masters");
  set.add("keep_depth_maps", &keep_depth_maps, "keep dense/depth_maps/");
  NeighbourOptions& n = neighbours;
  set.add("max_neighbours", &n.max_neighbours, "images matched against each master");
  set.add("min_shared_points", &n.min_shared_points, "sparse points a neighbour must share");
  set.add("min_angle_deg", &n.min_angle_deg, "deg: smallest median triangulation angle");
  set.add("max_angle_deg", &n.max_angle_deg, "deg: largest median triangulation angle");
  set.add("good_angle_deg", &n.good_angle_deg, "deg: smaller angles are down-weighted");
  set.add("depth_percentile", &n.depth_percentile,
          "fraction of the master's sparse depths cut at each end");
  set.add("depth_margin", &n.depth_margin, "the depth range widened by this fraction");
  set.add("min_depth_points", &n.min_depth_points, "sparse points a master must see");
  MatcherOptions& m = matcher;
  set.add("pyramid_levels", &m.pyramid_levels, "levels of the coarse-to-fine pyramid");
  set.add("min_level_size", &m.min_level_size, "px: smallest pyramid level (longer side)");
  set.add("window_radius", &m.window_radius, "px: NCC window is (2r+1)^2");
  set.add("best_k", &m.best_k, "the cost averages the k best neighbours' NCC");
  set.add("label_px", &m.label_px, "px of epipolar displacement per depth label");
  set.add("max_labels", &m.max_labels, "labels of the coarsest level's full search");
  set.add("search_labels", &m.search_labels, "labels per pixel at finer levels");
  set.add("range_margin", &m.range_margin, "labels added around the coarser level's range");
  set.add("p1", &m.p1, "SGM penalty for a one-label change (512 = 1 unit of 1 - NCC)");
  set.add("p2", &m.p2, "SGM penalty for larger jumps");
  set.add("p2_edge_grey", &m.p2_edge_grey, "grey levels: P2 / (1 + |dI| / this)");
  set.add("directions", &m.directions, "SGM paths: 4 or 8");
  set.add("min_ncc", &m.min_ncc, "a depth needs this aggregated NCC");
  set.add("uniqueness", &m.uniqueness, "margin of the best over the second-best cost");
  set.add("min_texture_grey", &m.min_texture_grey, "grey levels: window std below: no match");
  set.add("speckle_size", &m.speckle_size, "px: smaller isolated depth blobs are removed");
  set.add("speckle_labels", &m.speckle_labels, "labels: step separating speckle blobs");
  set.add("strip_rows", &m.strip_rows, "rows per cost strip (strips run in parallel)");
  FusionOptions& f = fusion;
  set.add("min_consistent", &f.min_consistent, "neighbours whose depth maps must agree");
  set.add("depth_tolerance", &f.depth_tolerance, "relative depth difference to agree");
  set.add("reprojection_px", &f.reprojection_px, "px: forward-backward reprojection error");
  set.add("normal_step", &f.normal_step, "px between the depths normals come from");
  set.add("pixel_step", &f.pixel_step, "px: new points start on this grid of a master");
}

nlohmann::json DenseStageOptions::toJson() const {
  const MatcherOptions& m = matcher;
  const NeighbourOptions& n = neighbours;
  return {{"max_image_size", max_image_size},
          {"min_registered_images", min_registered_images},
          {"min_points", min_points},
          {"neighbours",
           {{"max_neighbours", n.max_neighbours},
            {"min_shared_points", n.min_shared_points},
            {"min_angle_deg", n.min_angle_deg},
            {"max_angle_deg", n.max_angle_deg},
            {"good_angle_deg", n.good_angle_deg},
            {"depth_percentile", n.depth_percentile},
            {"depth_margin", n.depth_margin}}},
          {"matcher",
           {{"pyramid_levels", m.pyramid_levels},
            {"window_radius", m.window_radius},
            {"best_k", m.best_k},
            {"label_px", m.label_px},
            {"max_labels", m.max_labels},
            {"search_labels", m.search_labels},
            {"range_margin", m.range_margin},
            {"p1", m.p1},
            {"p2", m.p2},
            {"p2_edge_grey", m.p2_edge_grey},
            {"directions", m.directions},
            {"min_ncc", m.min_ncc},
            {"uniqueness", m.uniqueness},
            {"min_texture_grey", m.min_texture_grey},
            {"speckle_size", m.speckle_size}}},
          {"fusion",
           {{"min_consistent", fusion.min_consistent},
            {"depth_tolerance", fusion.depth_tolerance},
            {"reprojection_px", fusion.reprojection_px},
            {"pixel_step", fusion.pixel_step}}}};
}

nlohmann::json DenseStageResult::toJson() const {
  return {{"registered_images", registered_images},
          {"masters", masters},
          {"depth_maps", depth_maps},
          {"depth_map_size", {width, height}},
          {"depth_pixels", depth_pixels},
          {"depths_fused", depths_fused},
          {"depths_inconsistent", depths_inconsistent},
          {"points", points},
          {"masked_depth_maps", masked_depth_maps},
          {"seconds", seconds},
          {"neighbours", figures(neighbours)},
          {"matching", figures(matching)},
          {"fusion", figures(fusion)},
          {"writing", figures(writing)}};
}

DenseStageResult densify(const scene::Reconstruction& model, const fs::path& image_folder,
                         const fs::path& output_folder, const DenseStageOptions& options,
                         const ImageMasks& masks) {
  options.check();
  const auto start = Clock::now();
  DenseStageResult summary;
  summary.registered_images = model.images.size();
  if (static_cast<int>(model.images.size()) < options.min_registered_images) {
    throw StageError(kStage, "the sparse model has " + std::to_string(model.images.size()) +
                                 " registered images (at least " +
                                 std::to_string(options.min_registered_images) +
                                 " needed for dense matching)");
  }
  std::vector<MasterSelection> selections;
  {
    SubStage figures(summary.neighbours);
    selections = selectNeighbours(model, options.neighbours);
  }
  for (const MasterSelection& s : selections) summary.masters += s.usable() ? 1 : 0;
  if (summary.masters == 0) {
    throw StageError(kStage, "no registered image has a neighbour sharing >= " +
                                 std::to_string(options.neighbours.min_shared_points) +
                                 " sparse points at a triangulation angle in [" +
                                 std::to_string(options.neighbours.min_angle_deg) + ", " +
                                 std::to_string(options.neighbours.max_angle_deg) +
                                 "] deg and a depth range (" + std::to_string(model.points.size()) +
                                 " sparse points)");
  }

  StagedOutput output(output_folder);
  std::map<uint32_t, View> views;  // at the matching size, no images
  for (const auto& [id, image] : model.images) {
    View view = View::fromImage(model, image);
    const cv::Size size = limitedSize(view.width, view.height, options.max_image_size);
    views.emplace(id, view.scaled(size.width, size.height));
  }
  LruCache<View> loaded(options.image_cache);
  const auto loadedView = [&](uint32_t id) -> View& {
    return loaded.get(id, [&] {
      View view = views.at(id);
      loadImages(view, image_folder.string());
      return view;
    });
  };

  {  // neighbours.csv: what each master was matched with
    std::ostringstream csv;
    csv << "master,neighbours,shared_points,angles_deg,depth_min,depth_max\n";
    for (const MasterSelection& s : selections) {
      csv << model.images.at(s.master).name << ",";
      for (size_t i = 0; i < s.neighbours.size(); ++i) {
        csv << (i ? " " : "") << model.images.at(s.neighbours[i]).name;
      }
      csv << ",";
      for (size_t i = 0; i < s.neighbours.size(); ++i) csv << (i ? " " : "") << s.shared_points[i];
      csv << ",";
      for (size_t i = 0; i < s.neighbours.size(); ++i) {
        csv << (i ? " " : "") << std::fixed << std::setprecision(2) << s.angle_deg[i];
      }
      csv << "," << std::setprecision(6) << s.depth_min << "," << s.depth_max << "\n";
    }
    writeFileAtomically(output.path() / "neighbours.csv", csv.str());
  }

  std::map<uint32_t, bool> has_depth;
  {
    SubStage figures(summary.matching);
    Progress progress("dense: depth maps", "images", summary.masters);
    for (const MasterSelection& s : selections) {
      if (!s.usable()) continue;
      std::vector<View> neighbours;
      for (const uint32_t id : s.neighbours) neighbours.push_back(loadedView(id));
      const View& master = loadedView(s.master);
      // Loaded (and size-checked) before the matching: a bad mask fails at once.
      const cv::Mat mask =
          masks ? masks(master.name, {master.source_width, master.source_height}) : cv::Mat();
      DepthMapResult result =
          computeDepthMap(master, neighbours, s.depth_min, s.depth_max, options.matcher);
      if (!mask.empty()) {  // no depth, hence no fused point, from a masked pixel
        cv::Mat scaled;
        cv::resize(mask, scaled, result.depth.size(), 0, 0, cv::INTER_NEAREST);
        result.depth.setTo(0, scaled == 0);
        if (!result.confidence.empty()) result.confidence.setTo(0, scaled == 0);
        result.valid_pixels = static_cast<size_t>(cv::countNonZero(result.depth));
        ++summary.masked_depth_maps;
      }
      const fs::path file = depthMapPath(output.path(), master.name);
      fs::create_directories(file.parent_path());
      writeDenseArray(file, result.depth);
      has_depth[s.master] = true;
      ++summary.depth_maps;
      summary.depth_pixels += result.valid_pixels;
      if (summary.width == 0) {
        summary.width = result.depth.cols;
        summary.height = result.depth.rows;
      }
      progress.advance();
    }
  }

  FusedCloud cloud;
  {
    SubStage figures(summary.fusion);
    // Holds a master and all its neighbours at once (their references stay valid).
    LruCache<FusionView> fusion_views(
        std::max(options.image_cache, options.neighbours.max_neighbours + 1));
    const auto fusionView = [&](uint32_t id) -> FusionView& {
      return fusion_views.get(id, [&] {
        FusionView fv;
        fv.view = loadedView(id);
        fv.view.grey.release();
        const View& plain = views.at(id);
        if (has_depth.count(id)) {
          fv.depth = readDenseArray(depthMapPath(output.path(), plain.name));
        } else {
          fv.depth = cv::Mat(plain.height, plain.width, CV_32F, cv::Scalar(0));
        }
        fv.normals = normalsFromDepth(fv.depth, fv.view, options.fusion.normal_step);
        return fv;
      });
    };
    Fuser fuser(options.fusion);
    Progress progress("dense: fusion", "images", summary.depth_maps);
    for (const MasterSelection& s : selections) {
      if (!has_depth.count(s.master)) continue;
      // Load the neighbours first: the master must stay in the cache while they are used.
      std::vector<const FusionView*> neighbours;
      for (const uint32_t id : s.neighbours) {
        if (has_depth.count(id)) neighbours.push_back(&fusionView(id));
      }
      const FusionView& master = fusionView(s.master);
      const FusionStats stats = fuser.add(master, neighbours);
      summary.depths_fused += stats.depths;
      summary.depths_inconsistent += stats.inconsistent;
      progress.advance();
    }
    cloud = fuser.release();
  }
  summary.points = cloud.size();
  if (static_cast<int>(cloud.size()) < options.min_points || cloud.size() == 0) {
    throw StageError(kStage, "the fused cloud has " + std::to_string(cloud.size()) +
                                 " points (min_points = " + std::to_string(options.min_points) +
                                 "; " + std::to_string(summary.depth_pixels) + " depths in " +
                                 std::to_string(summary.depth_maps) + " depth maps, " +
                                 std::to_string(summary.depths_inconsistent) +
                                 " dropped as inconsistent across views)");
  }
  {
    SubStage figures(summary.writing);
    writeFusedViews(output.path() / "fused_views.bin", cloud.images);
    cloud.images = PointViews();
    scene::PlyData ply;
    ply.positions.reserve(cloud.size());
    for (const Eigen::Vector3f& p : cloud.positions) ply.positions.push_back(p.cast<double>());
    cloud.positions = {};
    ply.normals.reserve(ply.positions.size());
    for (const Eigen::Vector3f& n : cloud.normals) ply.normals.push_back(n.cast<double>());
    cloud.normals = {};
    ply.colors = std::move(cloud.colors);
    scene::writePly(output.path() / "fused.ply", ply);
    if (!options.keep_depth_maps) fs::remove_all(output.path() / "depth_maps");
    output.commit();
  }
  summary.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return summary;
}

DenseStageResult runDenseStage(const Survey& survey, const DenseStageOptions& options) {
  options.check();
  const Survey::PinholeWorkspace workspace = survey.pinholeWorkspace();
  Survey::requireExists(workspace.model / "images.txt", kStage, "sfm");
  Survey::requireExists(workspace.images, kStage, "correct");
  scene::Reconstruction model;
  try {
    model = scene::readColmapText(workspace.model);
  } catch (const std::exception& e) {
    throw StageError(kStage, std::string("cannot read the sparse model: ") + e.what());
  }
  const masks::SurveyMasks survey_masks(survey, kStage);
  const DenseStageResult summary = densify(
      model, workspace.images, survey.dense(), options,
      [&](const std::string& name, cv::Size size) { return survey_masks.forImage(name, size); });
  nlohmann::json section = summary.toJson();
  section["options"] = options.toJson();
  updateReport(survey.report(), kStage, section);
  return summary;
}

StageReport DenseStage::runWith(const Survey& survey, const DenseStageOptions& options) const {
  const DenseStageResult result = runDenseStage(survey, options);
  std::ostringstream line;
  line << "dense: " << result.depth_maps << " depth maps (" << result.width << "x" << result.height
       << " px), " << result.points << " points (" << result.depths_inconsistent
       << " depths dropped as inconsistent) in " << result.seconds << " s; "
       << (survey.dense() / "fused.ply").string();
  StageReport report;
  report.lines.push_back(line.str());
  report.summary = std::to_string(result.depth_maps) + " depth maps, " +
                   std::to_string(result.points) + " points";
  return report;
}

}  // namespace auv::recon::dense
