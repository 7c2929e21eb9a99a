#include "auv/recon/change/compare_stage.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <sstream>

#include <open3d/geometry/KDTreeFlann.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/TriangleMesh.h>

#include "auv/recon/change/change_map.h"
#include "auv/recon/change/change_view.h"
#include "auv/recon/change/clusters.h"
#include "auv/recon/change/local_bias.h"
#include "auv/recon/common/option_set.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/common/staged_output.h"
#include "auv/recon/scene/colmap_text.h"
#include "auv/recon/scene/mesh_io.h"
#include "auv/recon/scene/ply.h"

namespace fs = std::filesystem;

namespace auv::recon::change {

namespace {

constexpr const char* kStage = "compare";

double since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// One M3C2 comparison with the level of detection it was judged at.
struct Measured {
  std::vector<M3C2Point> points;
  nlohmann::json bias;  ///< the local bias taken out (report.json `local_bias`)
  double registration_error_m = 0.0;
  std::string error_source;
};

/// How the significant core points become regions (clusters.h). A region's volume takes the
/// net change within the measuring cylinder's radius of it; one independent measurement is
/// that cylinder's cross-section.
RegionOptions regionOptions(const CompareOptions& options) {
  RegionOptions regions;
  regions.spacing_m = options.core_spacing_m;
  regions.link_m = 1.5 * options.core_spacing_m;
  regions.min_area_m2 = options.min_cluster_area_m2;
  regions.min_change_m = options.min_change_m;
  const double radius_m = 0.5 * options.m3c2.projection_scale_m;
  regions.volume_margin_m = radius_m;
  regions.family_confidence = options.region_confidence;
  regions.footprint_m2 = M_PI * radius_m * radius_m;
  regions.level_of_detection_z = options.m3c2.confidence_z;
  regions.grow_at_measuring_scale = options.grow_regions;
  return regions;
}

/// The images fused into each point of a survey's dense cloud (dense/fused_views.bin), which
/// make M3C2's n the independent measurements; none when the dense stage did not write them
/// (a cloud made elsewhere). Throws StageError naming the file when it does not fit the cloud.
std::optional<PointSources> readSources(const Survey& survey, size_t points) {
  const fs::path file = survey.dense() / "fused_views.bin";
  if (!fs::exists(file)) return std::nullopt;
  PointSources sources;
  try {
    sources = dense::readPointViews(file);
  } catch (const std::exception& e) {
    throw StageError(kStage, e.what());
  }
  if (sources.size() != points) {
    throw StageError(kStage, file.string() + ": lists " + std::to_string(sources.size()) +
                                 " points, dense/fused.ply has " + std::to_string(points) +
                                 " (run the dense stage again)");
  }
  return sources;
}

/// Per core point, the direction to the nearest camera of survey 1 (the side its surface was
/// seen from); empty when survey 1 has no readable sparse model.
std::vector<Eigen::Vector3d> towardsCameras(const Survey& survey,
                                            const std::vector<Eigen::Vector3d>& core_points) {
  std::vector<Eigen::Vector3d> centres;
  try {
    for (const auto& [id, image] : scene::readColmapText(survey.sparse()).images) {
      centres.push_back(image.center());
    }
  } catch (const std::exception&) {
    return {};  // no model: the orientation option decides
  }
  if (centres.empty()) return {};
  Eigen::MatrixXd matrix(3, static_cast<Eigen::Index>(centres.size()));
  for (size_t i = 0; i < centres.size(); ++i) matrix.col(static_cast<Eigen::Index>(i)) = centres[i];
  const open3d::geometry::KDTreeFlann tree(matrix);
  std::vector<Eigen::Vector3d> hints(core_points.size());
  std::vector<int> index;
  std::vector<double> distance2;
  for (size_t i = 0; i < core_points.size(); ++i) {
    tree.SearchKNN(core_points[i], 1, index, distance2);
    hints[i] = centres[static_cast<size_t>(index[0])] - core_points[i];
  }
  return hints;
}

/// Survey 2's mesh in survey 1's frame, each vertex coloured by the change at the nearest core
/// point within `reach_m` (grey beyond: not compared), written to `file` and returned. Nothing
/// when survey 2 has no mesh.
std::optional<open3d::geometry::TriangleMesh> writeChangeMesh(
    const Survey& later, const Eigen::Matrix4d& transform,
    const std::vector<Eigen::Vector3d>& cores, const std::vector<M3C2Point>& comparison,
    double reach_m, double scale_m, const fs::path& file) {
  if (!fs::exists(later.mesh() / "mesh.ply")) return std::nullopt;
  open3d::geometry::TriangleMesh mesh = scene::readMesh(later.mesh() / "mesh.ply", kStage);
  mesh.Transform(transform);
  Eigen::MatrixXd matrix(3, static_cast<Eigen::Index>(cores.size()));
  for (size_t i = 0; i < cores.size(); ++i) matrix.col(static_cast<Eigen::Index>(i)) = cores[i];
  const open3d::geometry::KDTreeFlann tree(matrix);
  mesh.vertex_colors_.assign(mesh.vertices_.size(), Eigen::Vector3d::Constant(0.7));
  std::vector<int> index;
  std::vector<double> distance2;
  for (size_t v = 0; v < mesh.vertices_.size(); ++v) {
    if (tree.SearchKNN(mesh.vertices_[v], 1, index, distance2) > 0 &&
        distance2[0] <= reach_m * reach_m) {
      mesh.vertex_colors_[v] = changeColour(comparison[static_cast<size_t>(index[0])], scale_m);
    }
  }
  scene::writeMeshPly(file, mesh);
  return mesh;
}

/// change/changes.ply: the core points with their normals and the comparison as scalar fields.
scene::PlyData changesPly(const std::vector<Eigen::Vector3d>& cores,
                          const std::vector<M3C2Point>& comparison,
                          const AppearanceResult& appearance,
                          const std::vector<M3C2Point>* detection) {
  scene::PlyData ply;
  ply.positions = cores;
  std::vector<float> distance, lod, flag, delta_e, colour_flag;
  for (size_t i = 0; i < comparison.size(); ++i) {
    const M3C2Point& p = comparison[i];
    ply.normals.push_back(p.normal);
    distance.push_back(static_cast<float>(p.distance));
    lod.push_back(static_cast<float>(p.level_of_detection));
    flag.push_back(p.significant ? 1.0f : 0.0f);
    delta_e.push_back(static_cast<float>(appearance.delta_e[i]));
    colour_flag.push_back(appearance.significant[i] ? 1.0f : 0.0f);
  }
  // CloudCompare loads PLY properties named scalar_<name> as the scalar fields <name>.
  ply.scalars = {{"scalar_distance", distance},
                 {"scalar_level_of_detection", lod},
                 {"scalar_significant", flag},
                 {"scalar_delta_e", delta_e},
                 {"scalar_appearance_significant", colour_flag}};
  if (detection) {
    std::vector<float> coarse_distance, coarse_lod, coarse_flag;
    for (const M3C2Point& p : *detection) {
      coarse_distance.push_back(static_cast<float>(p.distance));
      coarse_lod.push_back(static_cast<float>(p.level_of_detection));
      coarse_flag.push_back(p.significant ? 1.0f : 0.0f);
    }
    ply.scalars.push_back({"scalar_detection_distance", coarse_distance});
    ply.scalars.push_back({"scalar_detection_level_of_detection", coarse_lod});
    ply.scalars.push_back({"scalar_detection_significant", coarse_flag});
  }
  return ply;
}

/// The appearance change, apart from the shape's: where the shape changed significantly the
/// colour is not compared. Not measured when a cloud has no colours.
nlohmann::json appearanceJson(const AppearanceResult& r,
                              const std::vector<AppearanceCluster>& clusters, bool coloured) {
  if (!coloured) return {{"measured", false}, {"why", "a dense cloud has no colours"}};
  nlohmann::json json = {{"measured", true},
                         {"normalisation",
                          {{"gain_rgb", {r.gain.x(), r.gain.y(), r.gain.z()}},
                           {"offset_rgb", {r.offset.x(), r.offset.y(), r.offset.z()}}}},
                         {"median_delta_e", r.median_delta_e},
                         {"threshold_delta_e", r.threshold},
                         {"core_points_measured", r.measured},
                         {"core_points_significant", r.significant_count},
                         {"clusters", nlohmann::json::array()}};
  for (const AppearanceCluster& c : clusters) json["clusters"].push_back(appearanceClusterJson(c));
  return json;
}

/// The change shown at full colour: the largest region's, or 0.1 m without regions.
double colourScale(const std::vector<ChangeCluster>& clusters) {
  double scale_m = 0.0;
  for (const ChangeCluster& c : clusters) {
    scale_m = std::max(scale_m, std::abs(c.max_abs_distance_m));
  }
  return scale_m > 0.0 ? scale_m : 0.1;
}

}  // namespace

void CompareOptions::check() const {
  if (later.empty()) throw OptionError("survey-2: the later survey is required");
  coregistration.check();
  m3c2.check();
  AUV_RECON_CHECK_OPTION(core_spacing_m > 0, core_spacing_m, "must be > 0");
  AUV_RECON_CHECK_OPTION(bias_radius_m == 0 || bias_radius_m >= 2 * core_spacing_m, bias_radius_m,
                         "must be 0 (off) or >= 2 core spacings");
  AUV_RECON_CHECK_OPTION(min_cluster_area_m2 >= 0, min_cluster_area_m2, "must be >= 0");
  AUV_RECON_CHECK_OPTION(min_change_m >= 0, min_change_m, "must be >= 0");
  AUV_RECON_CHECK_OPTION(region_confidence >= 0 && region_confidence < 1, region_confidence,
                         "must be in [0, 1) (0: every region with a significant point)");
  AUV_RECON_CHECK_OPTION(detection_scale >= 1 && detection_scale <= 10, detection_scale,
                         "must be in [1, 10] (1: one scale)");
  appearance.check();
}

void CompareOptions::bind(OptionSet& set) {
  set.positional("survey-2", &later,
                 "the later survey (reads dense/fused.ply; writes change/ and report.json's "
                 "`compare` section)");
  set.add("core_spacing_m", &core_spacing_m, "m: survey 1's cloud thinned to core points");
  set.add("bias_radius_m", &bias_radius_m,
          "m: the surveys' smooth deformation (median distance within it) is taken out; 0 = off");
  set.add("min_change_m", &min_change_m,
          "m: the smallest change of interest: regions where less than min_cluster_area_m2 "
          "changed by at least this much are dropped");
  set.add("min_cluster_area_m2", &min_cluster_area_m2,
          "m²: smaller clusters of significant change are dropped");
  set.add("region_confidence", &region_confidence,
          "a region is kept when its mean change is significant at this confidence over the "
          "whole site (Bonferroni over its independent measurements); 0 = off");
  set.add("detection_scale", &detection_scale,
          "> 1: regions found by M3C2 at this multiple of d and D, measured at d and D");
  set.add("grow_regions", &grow_regions,
          "at two scales, a region also takes the linked core points significant at d and D "
          "with its sign (a small block's edges, which the coarse scale averages away)");
  set.add("normal_scale_m", &m3c2.normal_scale_m, "m: M3C2 normal scale D (diameter)");
  set.add("projection_scale_m", &m3c2.projection_scale_m,
          "m: M3C2 projection scale d (cylinder diameter)");
  set.add("max_depth_m", &m3c2.max_depth_m, "m: M3C2 cylinder half-length: the largest change");
  set.add("min_points", &m3c2.min_points, "M3C2: fewer points of a cloud in the cylinder: none");
  set.add("max_axis_angle_deg", &m3c2.max_axis_angle_deg,
          "deg: points whose normal is farther from the cylinder's axis lie along it, not counted "
          "(90: all)");
  set.add("registration_error_m", &m3c2.registration_error_m,
          "m: inside the level of detection (0: the co-registration's RMS on stable points)");
  set.add("appearance_radius_m", &appearance.radius_m,
          "m: colours of each cloud averaged within this of a core point");
  set.add("appearance_min_delta_e", &appearance.min_delta_e,
          "CIE ΔE*ab below which a colour change is never significant");
  set.add("appearance_threshold_sigmas", &appearance.threshold_sigmas,
          "a colour change is significant above median + k robust sigmas of ΔE over the site");
  set.add("voxel_m", &coregistration.voxel_m, "m: clouds thinned for the co-registration");
  set.add("max_correspondence_m", &coregistration.max_correspondence_m,
          "m: how far the navigation frames may disagree");
  set.add("stable_threshold_m", &coregistration.stable_threshold_m,
          "m: farther from survey 1's surface: changed, not aligned on");
  set.add("min_overlap", &coregistration.min_overlap,
          "share of survey 2 that must lie on survey 1 (else refused: another site?)");
  set.add("min_stable_fraction", &coregistration.min_stable_fraction,
          "share of the overlap that must be stable (else refused)");
}

nlohmann::json runCompare(const Survey& survey, const CompareOptions& options) {
  options.check();
  const auto start = std::chrono::steady_clock::now();
  const Survey later(options.later);
  open3d::geometry::PointCloud first =
      scene::readCloud(survey.dense() / "fused.ply", kStage, "dense");
  open3d::geometry::PointCloud second =
      scene::readCloud(later.dense() / "fused.ply", kStage, "dense");
  std::optional<PointSources> sources1 = readSources(survey, first.points_.size());
  std::optional<PointSources> sources2 = readSources(later, second.points_.size());
  if (!sources1 || !sources2) sources1 = sources2 = std::nullopt;  // n alike on both sides
  // A cloud from elsewhere (a laser scan) may come without the normals fused.ply carries.
  std::string point_normals = "read from dense/fused.ply";
  for (open3d::geometry::PointCloud* cloud : {&first, &second}) {
    if (!cloud->HasNormals()) {
      point_normals = "estimated where fused.ply had none (radius d/2, 30 neighbours)";
      cloud->EstimateNormals(
          open3d::geometry::KDTreeSearchParamHybrid(0.5 * options.m3c2.projection_scale_m, 30));
    }
  }
  const double read_s = since(start);

  auto phase = std::chrono::steady_clock::now();
  CoregistrationResult aligned;
  try {
    aligned = coregister(first.points_, second.points_, Eigen::Matrix4d::Identity(),
                         options.coregistration);
  } catch (const CoregistrationError& e) {
    throw StageError(kStage,
                     survey.root().string() + " and " + later.root().string() + ": " + e.what());
  }
  const double coregistration_s = since(phase);
  second.Transform(aligned.transform);  // survey 2 in survey 1's frame

  phase = std::chrono::steady_clock::now();
  const std::vector<Eigen::Vector3d> cores = first.VoxelDownSample(options.core_spacing_m)->points_;
  const std::vector<Eigen::Vector3d> hints = towardsCameras(survey, cores);
  // One M3C2 pass at `scales`' d and D, the surveys' smooth deformation taken out, and the
  // level of detection with the registration error that is left.
  const auto compareAt = [&](const M3C2Options& scales) {
    Measured out;
    M3C2Options m3c2_options = scales;
    const bool given_error = m3c2_options.registration_error_m > 0.0;
    if (!given_error) m3c2_options.registration_error_m = aligned.rms_m;
    out.points = m3c2({first.points_, sources1 ? &*sources1 : nullptr, &first.normals_},
                      {second.points_, sources2 ? &*sources2 : nullptr, &second.normals_}, cores,
                      m3c2_options, hints);
    out.bias = {{"radius_m", options.bias_radius_m}};
    out.error_source = given_error ? "option" : "co-registration rms";
    if (options.bias_radius_m > 0.0) {
      const LocalBias bias = removeLocalBias(cores, out.points, options.bias_radius_m);
      out.bias["median_abs_bias_m"] = bias.median_abs_bias_m;
      out.bias["residual_sigma_m"] = bias.residual_sigma_m;
      if (!given_error) {
        m3c2_options.registration_error_m = bias.residual_sigma_m;
        out.error_source = "residual spread after the local bias";
      }
      applyLevelOfDetection(out.points, m3c2_options.registration_error_m,
                            m3c2_options.confidence_z);
    }
    out.registration_error_m = m3c2_options.registration_error_m;
    return out;
  };
  const Measured fine = compareAt(options.m3c2);
  // The points at d and D (changes.ply, the map, the coloured mesh); the regions from
  // `detection` when there is one.
  const std::vector<M3C2Point>& comparison = fine.points;
  std::optional<Measured> detection;
  if (options.detection_scale > 1.0) {
    M3C2Options coarse = options.m3c2;
    coarse.normal_scale_m *= options.detection_scale;
    coarse.projection_scale_m *= options.detection_scale;
    detection = compareAt(coarse);
  }
  const RegionOptions region_options = regionOptions(options);
  const std::vector<ChangeCluster> clusters =
      findRegions(cores, detection ? detection->points : comparison,
                  detection ? &comparison : nullptr, region_options);
  const double m3c2_s = since(phase);

  phase = std::chrono::steady_clock::now();
  std::vector<char> shape_changed(comparison.size());
  for (size_t i = 0; i < comparison.size(); ++i) shape_changed[i] = comparison[i].significant;
  const bool coloured = first.HasColors() && second.HasColors();
  const AppearanceResult appearance =
      compareAppearance(first.points_, first.colors_, second.points_, second.colors_, cores,
                        shape_changed, options.appearance);
  const std::vector<AppearanceCluster> appearance_clusters =
      clusterAppearance(cores, appearance, options.core_spacing_m, 1.5 * options.core_spacing_m,
                        options.min_cluster_area_m2);
  const double appearance_s = since(phase);

  size_t valid = 0, significant = 0;
  for (const M3C2Point& p : comparison) {
    valid += p.valid();
    significant += p.significant;
  }

  nlohmann::json report = {
      {"survey_1", fs::absolute(survey.root()).lexically_normal().string()},
      {"survey_2", fs::absolute(later.root()).lexically_normal().string()},
      {"options",
       {{"core_spacing_m", options.core_spacing_m},
        {"min_cluster_area_m2", options.min_cluster_area_m2},
        {"min_change_m", options.min_change_m},
        {"bias_radius_m", options.bias_radius_m},
        {"detection_scale", options.detection_scale},
        {"grow_regions", options.grow_regions},
        {"volume_margin_m", region_options.volume_margin_m},
        {"region_confidence", options.region_confidence},
        {"region_footprint_m2", region_options.footprint_m2},
        {"level_of_detection_z", region_options.level_of_detection_z},
        {"max_axis_angle_deg", options.m3c2.max_axis_angle_deg}}},
      {"registration",
       {{"rms_m", aligned.rms_m},
        {"overlap", aligned.overlap},
        {"stable_fraction", aligned.stable_fraction},
        {"rounds", aligned.rounds},
        {"transform_2_to_1", {}}}},
      {"level_of_detection_registration_error_m", fine.registration_error_m},
      {"level_of_detection_registration_error_source", fine.error_source},
      {"local_bias", fine.bias},
      {"level_of_detection_n",
       sources1 ? "distinct images fused into the cylinder's points" : "points in the cylinder"},
      {"orientation", hints.empty() ? "option" : "towards survey 1's cameras"},
      {"point_normals", point_normals},
      {"core_points", cores.size()},
      {"core_points_measured", valid},
      {"core_points_significant", significant},
      {"clusters", nlohmann::json::array()},
      {"appearance", appearanceJson(appearance, appearance_clusters, coloured)},
      {"seconds",
       {{"read", read_s},
        {"coregistration", coregistration_s},
        {"m3c2", m3c2_s},
        {"appearance", appearance_s}}}};
  for (int r = 0; r < 4; ++r) {
    report["registration"]["transform_2_to_1"].push_back(
        {aligned.transform(r, 0), aligned.transform(r, 1), aligned.transform(r, 2),
         aligned.transform(r, 3)});
  }
  if (detection) {
    report["detection"] = {
        {"scale", options.detection_scale},
        {"normal_scale_m", options.m3c2.normal_scale_m * options.detection_scale},
        {"projection_scale_m", options.m3c2.projection_scale_m * options.detection_scale},
        {"level_of_detection_registration_error_m", detection->registration_error_m},
        {"local_bias", detection->bias}};
  }
  for (const ChangeCluster& c : clusters) report["clusters"].push_back(clusterJson(c));

  StagedOutput staged(later.root() / "change");
  scene::writePly(
      staged.path() / "changes.ply",
      changesPly(cores, comparison, appearance, detection ? &detection->points : nullptr));
  const double scale_m = colourScale(clusters);
  writeChangeMap(staged.path() / "change_map.png", cores, comparison, options.core_spacing_m,
                 scale_m);
  const std::optional<open3d::geometry::TriangleMesh> coloured_mesh =
      writeChangeMesh(later, aligned.transform, cores, comparison,
                      // a changed surface lies up to max_depth from its core point
                      std::hypot(2.0 * options.core_spacing_m, options.m3c2.max_depth_m), scale_m,
                      staged.path() / "mesh_change.ply");
  report["coloured_mesh"] =
      coloured_mesh ? "mesh_change.ply" : "none: survey 2 has no mesh/mesh.ply";
  if (coloured_mesh) writeChangeView(staged.path() / "change_view.png", *coloured_mesh);
  writeFileAtomically(staged.path() / "report.json", report.dump(2) + "\n");
  staged.commit();
  report["seconds"]["total"] = since(start);
  nlohmann::json section = report;
  section.erase("clusters");
  section["clusters"] = clusters.size();
  if (section["appearance"].contains("clusters"))
    section["appearance"]["clusters"] = appearance_clusters.size();
  updateReport(later.report(), kStage, section);
  return report;
}

StageReport CompareStage::runWith(const Survey& survey, const CompareOptions& options) const {
  const nlohmann::json r = runCompare(survey, options);
  const fs::path folder = Survey(options.later).root() / "change";
  std::ostringstream line;
  line << kStage << ": registered on " << 100.0 * r["registration"]["stable_fraction"].get<double>()
       << " % stable surface (rms " << r["registration"]["rms_m"].get<double>() << " m); "
       << r["core_points_significant"].get<size_t>() << " of "
       << r["core_points_measured"].get<size_t>() << " core points changed significantly, "
       << r["clusters"].size() << " regions -> " << folder.string();
  StageReport report;
  report.lines.push_back(line.str());
  for (const auto& c : r["clusters"]) {
    std::ostringstream region;
    region << kStage << ": region of " << c["area_m2"].get<double>() << " m², mean "
           << c["mean_distance_m"].get<double>() << " m, +" << c["volume_gained_m3"].get<double>()
           << " / -" << c["volume_lost_m3"].get<double>() << " m³ at ("
           << c["centroid"][0].get<double>() << ", " << c["centroid"][1].get<double>() << ", "
           << c["centroid"][2].get<double>() << ")";
    report.lines.push_back(region.str());
  }
  const nlohmann::json& colour = r["appearance"];
  if (colour["measured"].get<bool>()) {
    std::ostringstream line2;
    line2 << kStage << ": appearance: " << colour["core_points_significant"].get<size_t>() << " of "
          << colour["core_points_measured"].get<size_t>() << " core points changed colour (ΔE*ab > "
          << colour["threshold_delta_e"].get<double>() << " after normalising survey 2's colours), "
          << colour["clusters"].size() << " regions";
    report.lines.push_back(line2.str());
  }
  std::ostringstream summary;
  summary << r["clusters"].size() << " changed regions";
  report.summary = summary.str();
  return report;
}

}  // namespace auv::recon::change
