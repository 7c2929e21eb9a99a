// The whole evaluation on a synthetic survey of a known world: a seabed with a rock, a
// simulator-like run folder, and a survey whose model is the truth moved by a known
// similarity. Bad inputs give clear errors and leave evaluation.json alone; the command's
// exit codes.
#include "auv/recon/evaluate/evaluator.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

#include "auv/recon/common/stage_error.h"
#include "auv/recon/evaluate/ground_truth.h"
#include "auv/recon/evaluate/image_matching.h"
#include "auv/recon/evaluate/well_imaged_region.h"
#include "synthetic_survey.h"

namespace auv::recon::evaluate {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::SyntheticSurvey;

TEST_F(SyntheticSurvey, PerfectReconstructionAlignsAndScoresOne) {
  const json r = evaluateSurvey(Survey(survey_), run_, quickOptions());
  EXPECT_EQ(r["images"]["matched_to_truth"], 13);
  EXPECT_EQ(r["images"]["keyframes"], 13);
  EXPECT_NEAR(r["alignment"]["scale"].get<double>(), sim_.scale, 1e-6);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(r["alignment"]["translation"][i].get<double>(), sim_.translation(i), 1e-5);
  }
  EXPECT_LT(r["camera_error"]["position_m"]["max"].get<double>(), 1e-6);
  EXPECT_LT(r["camera_error"]["rotation_deg"]["max"].get<double>(), 1e-4);
  // The region: the seabed strip under the 13 keyframes (about 9.5 m x 4 m less the rock's
  // shadow) plus the rock's top and sides.
  const double area = r["region"]["area_well_imaged_m2"];
  EXPECT_GT(area, 25.0);
  EXPECT_LT(area, 45.0);
  for (double t : {0.02, 0.05, 0.1, 0.2}) {
    EXPECT_GT(fscore(r, "dense", t), 0.99) << t;
    EXPECT_GT(fscore(r, "mesh", t), 0.99) << t;
  }
  // The sparse cloud is exact but thin: precision 1, recall below 1 at 2 cm.
  const auto& sparse = r["surfaces"]["sparse"]["thresholds"][0];
  EXPECT_DOUBLE_EQ(sparse["precision"].get<double>(), 1.0);
  EXPECT_LT(sparse["recall"].get<double>(), 0.5);
  EXPECT_EQ(r["texture"]["status"],
            "no textured model (" + (survey_ / "textured" / "model.obj").string() + ")");
  // evaluation.json and the report section.
  std::ifstream in(survey_ / "evaluation.json");
  const json written = json::parse(in);
  EXPECT_EQ(written["images"]["matched_to_truth"], 13);
  std::ifstream report_in(survey_ / "report.json");
  const json report = json::parse(report_in);
  EXPECT_GT(report["stages"]["evaluate"]["fscore_dense_5cm"].get<double>(), 0.99);
}

TEST_F(SyntheticSurvey, ShiftedDenseCloudFailsBelowTheShift) {
  writeDense(0.03);  // 3 cm too deep
  const json r = evaluateSurvey(Survey(survey_), run_, quickOptions());
  // The rock's top moves 3 cm down too, but its sides stay within 3 cm of themselves: the
  // 2 cm score is the fraction of points on the sides.
  EXPECT_LT(fscore(r, "dense", 0.02), 0.35);
  EXPECT_GT(fscore(r, "dense", 0.05), 0.99);
  EXPECT_GT(fscore(r, "mesh", 0.02), 0.99);  // the mesh did not move
}

TEST_F(SyntheticSurvey, NamesThatDoNotMatchTheTruth) {
  evaluateSurvey(Survey(survey_), run_, quickOptions());
  const std::string before = [&] {
    std::ifstream in(survey_ / "evaluation.json");
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  // The keyframe index names another video: nothing matches.
  fs::remove(survey_ / "keyframes" / "left" / "index.csv");
  {
    std::ofstream index(survey_ / "keyframes" / "left" / "index.csv");
    index << "file,video,frame\n";
    for (int f = 0; f < 25; f += 2) {
      char file[64];
      std::snprintf(file, sizeof(file), "left_0001_%06d.png", f);
      index << file << ",right_0001.mp4," << f << "\n";
    }
  }
  try {
    evaluateSurvey(Survey(survey_), run_, quickOptions());
    FAIL() << "unmatched names accepted";
  } catch (const StageError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("only 0 of 13 registered images match"), std::string::npos) << message;
    EXPECT_NE(message.find("left/left_0001_000000.png"), std::string::npos) << message;
  }
  std::ifstream in(survey_ / "evaluation.json");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), before);  // left intact
}

TEST_F(SyntheticSurvey, MissingInputsAreNamed) {
  try {
    evaluateSurvey(Survey(survey_), root_ / "no_run", quickOptions());
    FAIL();
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("no_run: no such run folder"), std::string::npos)
        << e.what();
  }
  fs::remove(run_ / "ground_truth" / "cameras.txt");
  try {
    evaluateSurvey(Survey(survey_), run_, quickOptions());
    FAIL();
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("cameras.txt not found"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("auv sim render"), std::string::npos) << e.what();
  }
  fs::remove_all(survey_ / "sparse");
  try {
    evaluateSurvey(Survey(survey_), run_, quickOptions());
    FAIL();
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("auv recon sfm"), std::string::npos) << e.what();
  }
  EvaluateOptions bad = quickOptions();
  bad.thresholds_m = "0.05,-1";
  try {
    evaluateSurvey(Survey(survey_), run_, bad);
    FAIL();
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("thresholds_m = 0.05,-1"), std::string::npos) << e.what();
  }
}

TEST_F(SyntheticSurvey, GroundTruthFramesAndMeshInTheWorldFrame) {
  const GroundTruth truth = GroundTruth::load(run_);
  EXPECT_EQ(truth.frames().size(), 25u);
  const GroundTruthFrame* frame = truth.find("left_0001#4");
  ASSERT_NE(frame, nullptr);
  EXPECT_EQ(frame->camera, "left");
  EXPECT_EQ(frame->frame, 4);
  EXPECT_EQ(truth.cameraNames(), std::vector<std::string>{"left"});
  EXPECT_DOUBLE_EQ(truth.visibility(), 6.0);
  // The z-up PLY maps back onto the NED world it was written from.
  const auto mesh = truth.worldMesh();
  ASSERT_EQ(mesh->vertices_.size(), world_.vertices_.size());
  for (size_t i = 0; i < world_.vertices_.size(); i += 37) {
    EXPECT_LT((mesh->vertices_[i] - world_.vertices_[i]).norm(), 1e-5);
  }
  EXPECT_EQ(truth.trueTrajectory().size(), 25u);
  // Keyframe sources and name parsing.
  const auto sources = readKeyframeSources(survey_ / "keyframes");
  ASSERT_EQ(sources.at("left").size(), 13u);
  EXPECT_EQ(sources.at("left")[1].key(), "left_0001#2");
  std::string stem;
  int64_t f = 0;
  EXPECT_TRUE(parseKeyframeName("forward_0002_000123.png", stem, f));
  EXPECT_EQ(stem, "forward_0002");
  EXPECT_EQ(f, 123);
  EXPECT_FALSE(parseKeyframeName("forward.png", stem, f));
  EXPECT_FALSE(parseKeyframeName("forward_12a.png", stem, f));
}

TEST_F(SyntheticSurvey, MalformedIndexIsNamed) {
  std::ofstream(survey_ / "keyframes" / "left" / "index.csv") << "file,video,frame\nx.png,v,abc\n";
  try {
    readKeyframeSources(survey_ / "keyframes");
    FAIL();
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("index.csv:2: frame 'abc'"), std::string::npos)
        << e.what();
  }
}

TEST_F(SyntheticSurvey, CommandExitCodes) {
  const std::string tool = AUV_RECON_TOOL;
  const std::string log = (root_ / "log.txt").string();
  auto run = [&](const std::string& arguments) {
    const int status = std::system((tool + " " + arguments + " > " + log + " 2>&1").c_str());
    return WEXITSTATUS(status);
  };
  auto output = [&] {
    std::ifstream in(log);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_EQ(run("evaluate " + survey_.string() + " --ground-truth " + run_.string()), 0)
      << output();
  EXPECT_NE(output().find("13 of 13 registered images matched"), std::string::npos) << output();
  EXPECT_NE(output().find("F@5cm 1.000"), std::string::npos) << output();
  EXPECT_EQ(
      run("evaluate " + survey_.string() + " --ground-truth " + run_.string() + " --min-views 0"),
      2);
  EXPECT_NE(output().find("min_views = 0"), std::string::npos) << output();
  EXPECT_EQ(run("evaluate " + survey_.string()), 2);  // no --ground-truth, no simulation.json
  EXPECT_NE(output().find("--ground-truth"), std::string::npos) << output();
  EXPECT_EQ(run("evaluate " + survey_.string() + " --ground-truth " + (root_ / "x").string()), 1);
  EXPECT_NE(output().find("no such run folder"), std::string::npos) << output();
  // simulation.json names the run (relative to the survey).
  std::ofstream(survey_ / "simulation.json") << R"({"ground_truth_run": "../run"})";
  EXPECT_EQ(run("evaluate " + survey_.string()), 0) << output();
}

TEST_F(SyntheticSurvey, SimulationJsonNamesTheRunsRelativeToTheSurvey) {
  const Survey survey(survey_);
  EXPECT_TRUE(recordedGroundTruth(survey).empty());  // no simulation.json
  std::ofstream(survey_ / "simulation.json")
      << R"({"ground_truth_run": "../run", "true_texture_run": "/elsewhere/clear"})";
  EXPECT_EQ(recordedGroundTruth(survey), survey_ / "../run");
  EXPECT_EQ(recordedRun(survey, "true_texture_run"), fs::path("/elsewhere/clear"));
  EXPECT_TRUE(recordedRun(survey, "mission_run").empty());
  std::ofstream(survey_ / "simulation.json") << R"({"ground_truth_run": )";
  try {
    recordedRun(survey, "true_texture_run");
    FAIL() << "no exception";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("simulation.json"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace auv::recon::evaluate
