#include "auv/recon/dense/dense_stage.h"

#include <chrono>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <list>
#include <set>
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

namespace {

/// What every part of a dense run (whole, shard, merge) derives alike from the model: the
/// masters with their neighbours, and the views at the matching size (no images).
struct DensePlan {
  const scene::Reconstruction& model;
  std::vector<MasterSelection> selections;
  std::map<uint32_t, View> views;
  std::set<uint32_t> masters;  ///< the usable masters: each gets a depth map

  /// The usable masters of `shard`, in selection order: those whose rank is index mod count.
  std::vector<const MasterSelection*> mastersOf(Shard shard) const {
    std::vector<const MasterSelection*> mine;
    size_t rank = 0;
    for (const MasterSelection& s : selections) {
      if (s.usable() && rank++ % shard.count == static_cast<size_t>(shard.index)) {
        mine.push_back(&s);
      }
    }
    return mine;
  }
  /// Their image names, as shard.json lists them.
  nlohmann::json namesOf(Shard shard) const {
    nlohmann::json names = nlohmann::json::array();
    for (const MasterSelection* s : mastersOf(shard)) names.push_back(name(s->master));
    return names;
  }
  const std::string& name(uint32_t id) const { return model.images.at(id).name; }
};

DensePlan planDense(const scene::Reconstruction& model, const DenseStageOptions& options,
                    DenseStageResult& summary) {
  summary.registered_images = model.images.size();
  if (static_cast<int>(model.images.size()) < options.min_registered_images) {
    throw StageError(kStage, "the sparse model has " + std::to_string(model.images.size()) +
                                 " registered images (at least " +
                                 std::to_string(options.min_registered_images) +
                                 " needed for dense matching)");
  }
  DensePlan plan{model, {}, {}, {}};
  {
    SubStage figures(summary.neighbours);
    plan.selections = selectNeighbours(model, options.neighbours);
  }
  for (const MasterSelection& s : plan.selections) {
    if (s.usable()) plan.masters.insert(s.master);
  }
  summary.masters = plan.masters.size();
  if (summary.masters == 0) {
    throw StageError(kStage, "no registered image has a neighbour sharing >= " +
                                 std::to_string(options.neighbours.min_shared_points) +
                                 " sparse points at a triangulation angle in [" +
                                 std::to_string(options.neighbours.min_angle_deg) + ", " +
                                 std::to_string(options.neighbours.max_angle_deg) +
                                 "] deg and a depth range (" + std::to_string(model.points.size()) +
                                 " sparse points)");
  }
  for (const auto& [id, image] : model.images) {
    View view = View::fromImage(model, image);
    const cv::Size size = limitedSize(view.width, view.height, options.max_image_size);
    plan.views.emplace(id, view.scaled(size.width, size.height));
  }
  return plan;
}

/// Views with their images, a few kept in memory.
class LoadedViews {
 public:
  LoadedViews(const DensePlan& plan, const fs::path& image_folder, size_t capacity)
      : plan_(plan), image_folder_(image_folder.string()), cache_(capacity) {}
  View& get(uint32_t id) {
    return cache_.get(id, [&] {
      View view = plan_.views.at(id);
      loadImages(view, image_folder_);
      return view;
    });
  }

 private:
  const DensePlan& plan_;
  std::string image_folder_;
  LruCache<View> cache_;
};

/// neighbours.csv: what each master was matched with.
void writeNeighbours(const DensePlan& plan, const fs::path& folder) {
  std::ostringstream csv;
  csv << "master,neighbours,shared_points,angles_deg,depth_min,depth_max\n";
  for (const MasterSelection& s : plan.selections) {
    csv << plan.name(s.master) << ",";
    for (size_t i = 0; i < s.neighbours.size(); ++i) {
      csv << (i ? " " : "") << plan.name(s.neighbours[i]);
    }
    csv << ",";
    for (size_t i = 0; i < s.neighbours.size(); ++i) csv << (i ? " " : "") << s.shared_points[i];
    csv << ",";
    for (size_t i = 0; i < s.neighbours.size(); ++i) {
      csv << (i ? " " : "") << std::fixed << std::setprecision(2) << s.angle_deg[i];
    }
    csv << "," << std::setprecision(6) << s.depth_min << "," << s.depth_max << "\n";
  }
  writeFileAtomically(folder / "neighbours.csv", csv.str());
}

/// The depth maps of shard `shard`'s masters (every count-th usable one), into
/// `folder`/depth_maps/. Masked pixels get no depth.
void computeDepthMaps(const DensePlan& plan, const fs::path& image_folder, const fs::path& folder,
                      const DenseStageOptions& options, const ImageMasks& masks, Shard shard,
                      DenseStageResult& summary) {
  const std::vector<const MasterSelection*> mine = plan.mastersOf(shard);
  LoadedViews loaded(plan, image_folder, options.image_cache);
  SubStage figures(summary.matching);
  Progress progress("dense: depth maps", "images", mine.size());
  for (const MasterSelection* selection : mine) {
    const MasterSelection& s = *selection;
    std::vector<View> neighbours;
    for (const uint32_t id : s.neighbours) neighbours.push_back(loaded.get(id));
    const View& master = loaded.get(s.master);
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
    const fs::path file = depthMapPath(folder, master.name);
    fs::create_directories(file.parent_path());
    writeDenseArray(file, result.depth);
    ++summary.depth_maps;
    summary.depth_pixels += result.valid_pixels;
    if (summary.width == 0) {
      summary.width = result.depth.cols;
      summary.height = result.depth.rows;
    }
    progress.advance();
  }
}

/// Fuses the masters' depth maps under `folder`/depth_maps/ (every usable master has one) and
/// writes fused.ply and fused_views.bin there. Throws StageError below options.min_points.
void fuseAndWrite(const DensePlan& plan, const fs::path& image_folder, const fs::path& folder,
                  const DenseStageOptions& options, DenseStageResult& summary) {
  const std::set<uint32_t>& has_depth = plan.masters;
  FusedCloud cloud;
  {
    SubStage figures(summary.fusion);
    LoadedViews loaded(plan, image_folder, options.image_cache);
    // Holds a master and all its neighbours at once (their references stay valid).
    LruCache<FusionView> fusion_views(
        std::max(options.image_cache, options.neighbours.max_neighbours + 1));
    const auto fusionView = [&](uint32_t id) -> FusionView& {
      return fusion_views.get(id, [&] {
        FusionView fv;
        fv.view = loaded.get(id);
        fv.view.grey.release();
        const View& plain = plan.views.at(id);
        if (has_depth.count(id)) {
          fv.depth = readDenseArray(depthMapPath(folder, plain.name));
        } else {
          fv.depth = cv::Mat(plain.height, plain.width, CV_32F, cv::Scalar(0));
        }
        fv.normals = normalsFromDepth(fv.depth, fv.view, options.fusion.normal_step);
        return fv;
      });
    };
    Fuser fuser(options.fusion);
    Progress progress("dense: fusion", "images", has_depth.size());
    for (const MasterSelection& s : plan.selections) {
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
  SubStage figures(summary.writing);
  writeFusedViews(folder / "fused_views.bin", cloud.images);
  cloud.images = PointViews();
  scene::PlyData ply;
  ply.positions.reserve(cloud.size());
  for (const Eigen::Vector3f& p : cloud.positions) ply.positions.push_back(p.cast<double>());
  cloud.positions = {};
  ply.normals.reserve(ply.positions.size());
  for (const Eigen::Vector3f& n : cloud.normals) ply.normals.push_back(n.cast<double>());
  cloud.normals = {};
  ply.colors = std::move(cloud.colors);
  scene::writePly(folder / "fused.ply", ply);
  if (!options.keep_depth_maps) fs::remove_all(folder / "depth_maps");
}

}  // namespace

DenseStageResult densify(const scene::Reconstruction& model, const fs::path& image_folder,
                         const fs::path& output_folder, const DenseStageOptions& options,
                         const ImageMasks& masks) {
  options.check();
  const auto start = Clock::now();
  DenseStageResult summary;
  const DensePlan plan = planDense(model, options, summary);
  StagedOutput output(output_folder);
  writeNeighbours(plan, output.path());
  computeDepthMaps(plan, image_folder, output.path(), options, masks, Shard(), summary);
  fuseAndWrite(plan, image_folder, output.path(), options, summary);
  output.commit();
  summary.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return summary;
}

namespace {

/// The survey's sparse model and the folder of its (pinhole) images.
struct SurveyModel {
  scene::Reconstruction model;
  fs::path images;
};

SurveyModel readSurveyModel(const Survey& survey) {
  const Survey::PinholeWorkspace workspace = survey.pinholeWorkspace();
  Survey::requireExists(workspace.model / "images.txt", kStage, "sfm");
  Survey::requireExists(workspace.images, kStage, "correct");
  SurveyModel read{{}, workspace.images};
  try {
    read.model = scene::readColmapText(workspace.model);
  } catch (const std::exception& e) {
    throw StageError(kStage, std::string("cannot read the sparse model: ") + e.what());
  }
  return read;
}

void writeReport(const Survey& survey, const DenseStageResult& summary,
                 const DenseStageOptions& options, int shards) {
  nlohmann::json section = summary.toJson();
  section["options"] = options.toJson();
  if (shards > 1) section["shards"] = shards;
  updateReport(survey.report(), kStage, section);
}

/// Hard link where the filesystem allows (the shards' folder is in the survey), else a copy.
void linkOrCopy(const fs::path& from, const fs::path& to) {
  fs::create_directories(to.parent_path());
  std::error_code error;
  fs::create_hard_link(from, to, error);
  if (error) fs::copy_file(from, to, fs::copy_options::overwrite_existing);
}

}  // namespace

DenseStageResult runDenseStage(const Survey& survey, const DenseStageOptions& options) {
  options.check();
  const SurveyModel read = readSurveyModel(survey);
  const masks::SurveyMasks survey_masks(survey, kStage);
  const DenseStageResult summary = densify(
      read.model, read.images, survey.dense(), options,
      [&](const std::string& name, cv::Size size) { return survey_masks.forImage(name, size); });
  writeReport(survey, summary, options, 1);
  return summary;
}

size_t runDenseShard(const Survey& survey, const DenseStageOptions& options, Shard shard) {
  options.check();
  shard.check();
  const auto start = Clock::now();
  const SurveyModel read = readSurveyModel(survey);
  const masks::SurveyMasks survey_masks(survey, kStage);
  DenseStageResult summary;
  const DensePlan plan = planDense(read.model, options, summary);
  StagedOutput output(shardFolder(survey, kStage, shard));
  computeDepthMaps(
      plan, read.images, output.path(), options,
      [&](const std::string& name, cv::Size size) { return survey_masks.forImage(name, size); },
      shard, summary);
  // What the merge needs of this shard: which masters it holds (a shard of another model is
  // refused) and its figures.
  writeFileAtomically(
      output.path() / "shard.json",
      nlohmann::json{{"masters", plan.namesOf(shard)},
                     {"depth_pixels", summary.depth_pixels},
                     {"masked_depth_maps", summary.masked_depth_maps},
                     {"depth_map_size", {summary.width, summary.height}},
                     {"matching", figures(summary.matching)},
                     {"seconds", std::chrono::duration<double>(Clock::now() - start).count()}}
          .dump());
  output.commit();
  return summary.depth_maps;
}

DenseStageResult mergeDenseShards(const Survey& survey, const DenseStageOptions& options,
                                  int count) {
  options.check();
  Shard{0, count}.check();
  const auto start = Clock::now();
  const SurveyModel read = readSurveyModel(survey);
  DenseStageResult summary;
  const DensePlan plan = planDense(read.model, options, summary);
  StagedOutput output(survey.dense());
  double shard_seconds = 0;
  for (int index = 0; index < count; ++index) {
    const fs::path folder = shardFolder(survey, kStage, {index, count});
    const std::string which = "shard " + std::to_string(index) + " of " + std::to_string(count);
    const std::string rerun = " (`auv recon run " + survey.root().string() +
                              " --from dense --to dense --shard " + std::to_string(index) + "/" +
                              std::to_string(count) + "`)";
    if (!fs::exists(folder / "shard.json"))
      throw StageError(kStage, which + " has not run" + rerun);
    std::ifstream in(folder / "shard.json");
    const nlohmann::json shard = nlohmann::json::parse(in, nullptr, false);
    if (shard.is_discarded() || !shard.is_object()) {
      throw StageError(kStage,
                       (folder / "shard.json").string() + ": not a shard's JSON object" + rerun);
    }
    const nlohmann::json expected = plan.namesOf({index, count});
    if (shard.value("masters", nlohmann::json()) != expected) {
      throw StageError(kStage, which + " holds the depth maps of other masters than " +
                                   survey.sparse().string() + " now gives: run it again" + rerun);
    }
    for (const auto& name : expected) {
      const fs::path from = depthMapPath(folder, name.get<std::string>());
      if (!fs::exists(from)) {
        throw StageError(kStage, which + " lacks " + from.string() + ": run it again" + rerun);
      }
      linkOrCopy(from, depthMapPath(output.path(), name.get<std::string>()));
    }
    summary.depth_maps += expected.size();
    summary.depth_pixels += shard.value("depth_pixels", size_t{0});
    summary.masked_depth_maps += shard.value("masked_depth_maps", size_t{0});
    const nlohmann::json size = shard.value("depth_map_size", nlohmann::json::array({0, 0}));
    if (summary.width == 0 && size.is_array() && size.size() == 2 && size[0].is_number()) {
      summary.width = size[0].get<int>();
      summary.height = size[1].get<int>();
    }
    const nlohmann::json matching = shard.value("matching", nlohmann::json::object());
    summary.matching.seconds += matching.value("seconds", 0.0);
    summary.matching.cpu_seconds += matching.value("cpu_seconds", 0.0);
    summary.matching.peak_memory_bytes =
        std::max(summary.matching.peak_memory_bytes,
                 static_cast<size_t>(matching.value("peak_memory_mb", 0.0) * 1048576.0));
    shard_seconds += shard.value("seconds", 0.0);
  }
  writeNeighbours(plan, output.path());
  fuseAndWrite(plan, read.images, output.path(), options, summary);
  output.commit();
  fs::remove_all(survey.root() / ".shards" / kStage);
  // The work of the whole stage, as the features' merge counts it: the shards' and the merge's.
  summary.seconds = shard_seconds + std::chrono::duration<double>(Clock::now() - start).count();
  writeReport(survey, summary, options, count);
  return summary;
}

namespace {

StageReport reportOf(const Survey& survey, const DenseStageResult& result) {
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

}  // namespace

StageReport DenseStage::runWith(const Survey& survey, const DenseStageOptions& options) const {
  return reportOf(survey, runDenseStage(survey, options));
}

StageReport DenseStage::runShardWith(const Survey& survey, const DenseStageOptions& options,
                                     Shard shard) const {
  return shardReport("dense", shard,
                     std::to_string(runDenseShard(survey, options, shard)) + " depth maps");
}

StageReport DenseStage::mergeShardsWith(const Survey& survey, const DenseStageOptions& options,
                                        int count) const {
  return mergedReport(reportOf(survey, mergeDenseShards(survey, options, count)), count);
}

}  // namespace auv::recon::dense
