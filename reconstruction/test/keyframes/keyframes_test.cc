// Keyframe selection (paper section 3.1) on synthetic sequences with known motion: a camera
// panning over a random texture at a known speed, with blurred, dark and featureless frames and
// a scene cut; then the stage over a survey folder with real video files (written here with
// cv::VideoWriter), damaged videos and bad sidecars.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "auv/recon/common/option_set.h"
#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/keyframes/keyframes_stage.h"
#include "auv/recon/keyframes/selector.h"
#include "auv/recon/keyframes/video.h"

namespace fs = std::filesystem;
using namespace auv::recon;
using namespace auv::recon::keyframes;

namespace {

constexpr int kWidth = 320, kHeight = 240;
constexpr int kSpeed = 4;  // px per frame, to the left

/// A texture with corners at every scale: blurred noise plus random rectangles.
cv::Mat texture(int width, int height, unsigned seed) {
  cv::RNG rng(seed);
  cv::Mat noise(height, width, CV_8UC3);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 1.5);
  for (int i = 0; i < width * height / 400; ++i) {
    const cv::Point a(rng.uniform(0, width), rng.uniform(0, height));
    const cv::Point b = a + cv::Point(rng.uniform(4, 30), rng.uniform(4, 30));
    cv::rectangle(noise, a, b,
                  cv::Scalar(rng.uniform(0, 255), rng.uniform(0, 255), rng.uniform(0, 255)),
                  cv::FILLED);
  }
  return noise;
}

/// Frame i of a pan over `scene`: the window moves kSpeed px per frame.
cv::Mat panFrame(const cv::Mat& scene, int i) {
  return scene(cv::Rect(i * kSpeed, 0, kWidth, kHeight)).clone();
}

cv::Mat blurred(const cv::Mat& frame) {
  cv::Mat out;
  cv::GaussianBlur(frame, out, cv::Size(0, 0), 3.0);
  return out;
}

KeyframeOptions smallOptions() {
  KeyframeOptions o;
  o.analysis_width = 0;
  o.min_motion = 0.19;  // 60.8 px: a keyframe every 16 frames (64 px) at 4 px/frame
  o.candidate_frames = 5;
  return o;
}

std::vector<Keyframe> runSelector(KeyframeSelector& selector, int frames,
                                  const std::function<cv::Mat(int)>& frame) {
  std::vector<Keyframe> keyframes;
  for (int i = 0; i < frames; ++i) {
    if (auto k = selector.addFrame(i, frame(i))) keyframes.push_back(std::move(*k));
  }
  if (auto k = selector.finish()) keyframes.push_back(std::move(*k));
  return keyframes;
}

fs::path freshFolder(const std::string& name) {
  const fs::path folder = fs::temp_directory_path() /
                          ("auv_recon_keyframes_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

/// recordings/<camera>/<camera>_0001.<ext> of `frames` pan frames + sidecar (10 Hz camera
/// clock from 100 s, sim time from 0). Returns the video path.
fs::path writeRecording(const fs::path& survey, const std::string& camera, int frames,
                        const std::string& ext = "avi", int sidecar_rows = -1) {
  const fs::path folder = survey / "recordings" / camera;
  fs::create_directories(folder);
  const fs::path video = folder / (camera + "_0001." + ext);
  const cv::Mat scene = texture(kWidth + kSpeed * frames + 8, kHeight, 7);
  cv::VideoWriter writer(video.string(), cv::CAP_FFMPEG,
                         cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0,
                         cv::Size(kWidth, kHeight));
  EXPECT_TRUE(writer.isOpened()) << video;
  for (int i = 0; i < frames; ++i) writer.write(panFrame(scene, i));
  writer.release();
  std::ofstream sidecar(video.string() + ".frames.csv");
  sidecar << "frame,camera_time_s,sim_time_s\n";
  const int rows = sidecar_rows < 0 ? frames : sidecar_rows;
  for (int i = 0; i < rows; ++i) {
    sidecar << i << ',' << 100.0 + 0.1 * i << ',' << 0.1 * i << '\n';
  }
  return video;
}

std::vector<std::vector<std::string>> readCsv(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::stringstream row(line);
    std::string field;
    while (std::getline(row, field, ',')) fields.push_back(field);
    if (!line.empty() && line.back() == ',') fields.emplace_back();
    rows.push_back(fields);
  }
  return rows;
}

/// Runs the built `auv-recon` tool; returns the exit code, stderr in `err`.
int runTool(const std::string& arguments, std::string* err) {
  const fs::path log =
      fs::temp_directory_path() / ("auv_recon_kf_tool_" + std::to_string(::getpid()));
  const std::string command =
      std::string(AUV_RECON_TOOL) + " " + arguments + " >/dev/null 2>" + log.string();
  const int status = std::system(command.c_str());
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  *err = text.str();
  fs::remove(log);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

TEST(KeyframeSelector, PicksFramesAtTheSpacingOfTheKnownMotion) {
  const cv::Mat scene = texture(kWidth + kSpeed * 120, kHeight, 1);
  KeyframeSelector selector(smallOptions());
  const auto keyframes = runSelector(selector, 100, [&](int i) { return panFrame(scene, i); });
  // 4 px/frame, threshold 60.8 px: triggers 16 frames after a keyframe, chosen within the
  // 5-frame candidate window: spacing in [16, 20]; the first one in the first window.
  ASSERT_GE(keyframes.size(), 5u);
  EXPECT_LE(keyframes[0].frame, 4);
  EXPECT_EQ(keyframes[0].trigger, Trigger::START);
  for (size_t k = 1; k < keyframes.size(); ++k) {
    const int spacing = keyframes[k].frame - keyframes[k - 1].frame;
    EXPECT_GE(spacing, 16) << "keyframe " << k;
    EXPECT_LE(spacing, 20) << "keyframe " << k;
    EXPECT_EQ(keyframes[k].trigger, Trigger::MOTION);
    // The measured motion is the true one (4 px per frame since the last keyframe) within 1 px.
    EXPECT_NEAR(keyframes[k].motion_px, kSpeed * spacing, 1.0) << "keyframe " << k;
    EXPECT_GT(keyframes[k].tracked, 0.5 * keyframes[k - 1].features);
    EXPECT_EQ(keyframes[k].image.size(), cv::Size(kWidth, kHeight));
  }
  EXPECT_TRUE(selector.rejected().empty());
}

TEST(KeyframeSelector, AvoidsBlurredFramesAndReportsThem) {
  const cv::Mat scene = texture(kWidth + kSpeed * 120, kHeight, 2);
  // Three of every five frames blurred (sigma 3 px): every 5-frame window holds two sharp ones.
  auto is_blurred = [](int i) { return i % 5 < 3; };
  KeyframeSelector selector(smallOptions());
  const auto keyframes = runSelector(selector, 100, [&](int i) {
    const cv::Mat frame = panFrame(scene, i);
    return is_blurred(i) ? blurred(frame) : frame;
  });
  ASSERT_GE(keyframes.size(), 5u);
  for (const auto& k : keyframes) EXPECT_FALSE(is_blurred(k.frame)) << "frame " << k.frame;
  for (size_t k = 1; k < keyframes.size(); ++k) {
    const int spacing = keyframes[k].frame - keyframes[k - 1].frame;
    EXPECT_GE(spacing, 16) << triggerName(keyframes[k].trigger) << " motion "
                           << keyframes[k].motion_px << " tracked " << keyframes[k].tracked
                           << " of " << keyframes[k - 1].features;
    EXPECT_LE(spacing, 20);
  }
  // After the first keyframe (the blur reference), the blurred candidates are reported.
  const auto& rejected = selector.rejected();
  EXPECT_GE(rejected.size(), 2 * (keyframes.size() - 1));
  for (const auto& r : rejected) {
    EXPECT_TRUE(is_blurred(r.frame)) << "frame " << r.frame;
    EXPECT_EQ(r.reason, "blurry");
  }
  EXPECT_EQ(selector.counts().rejected_blurry, static_cast<int>(rejected.size()));
}

TEST(KeyframeSelector, RefusesDarkFrames) {
  const cv::Mat scene = texture(kWidth + kSpeed * 80, kHeight, 3);
  auto is_dark = [](int i) { return (i >= 16 && i <= 19) || i < 2; };
  KeyframeSelector selector(smallOptions());
  const auto keyframes = runSelector(selector, 60, [&](int i) {
    cv::Mat frame = panFrame(scene, i);
    if (is_dark(i)) frame *= 0.04;  // mean grey ~5
    return frame;
  });
  ASSERT_GE(keyframes.size(), 3u);
  for (const auto& k : keyframes) EXPECT_FALSE(is_dark(k.frame)) << "frame " << k.frame;
  std::set<int> dark;
  for (const auto& r : selector.rejected()) {
    EXPECT_EQ(r.reason, "dark") << "frame " << r.frame;
    dark.insert(r.frame);
  }
  EXPECT_TRUE(dark.count(0) && dark.count(1));  // in the first window
  EXPECT_GE(selector.counts().rejected_dark, 2);
}

TEST(KeyframeSelector, ANewSceneTriggersAKeyframeWhenTrackingIsLost) {
  const cv::Mat first = texture(kWidth + kSpeed * 80, kHeight, 4);
  const cv::Mat second = texture(kWidth + kSpeed * 80, kHeight, 5);
  KeyframeOptions options = smallOptions();
  options.min_motion = 0.9;  // motion alone would not trigger within the sequence
  KeyframeSelector selector(options);
  const auto keyframes = runSelector(selector, 50, [&](int i) {
    return i < 30 ? panFrame(first, i / 8) : panFrame(second, i / 8);  // slow pan, cut at 30
  });
  ASSERT_EQ(keyframes.size(), 2u);
  EXPECT_EQ(keyframes[1].trigger, Trigger::TRACKING_LOST);
  EXPECT_GE(keyframes[1].frame, 30);
  EXPECT_LE(keyframes[1].frame, 34);
  EXPECT_EQ(selector.counts().triggers_tracking, 1);
}

TEST(KeyframeSelector, FeaturelessFramesAreRefused) {
  // Open water: flat, so no sharpness either.
  KeyframeSelector water_selector(smallOptions());
  const cv::Mat water(kHeight, kWidth, CV_8UC3, cv::Scalar(120, 100, 30));
  EXPECT_TRUE(runSelector(water_selector, 12, [&](int) { return water; }).empty());
  ASSERT_EQ(water_selector.rejected().size(), 12u);
  for (const auto& r : water_selector.rejected()) EXPECT_EQ(r.reason, "blurry");
  // Sharp horizontal stripes: edges (a high Laplacian variance) but no corner to track.
  cv::Mat stripes(kHeight, kWidth, CV_8UC3, cv::Scalar(40, 40, 40));
  for (int y = 0; y < kHeight; y += 24) {
    stripes(cv::Rect(0, y, kWidth, 12)).setTo(cv::Scalar(200, 200, 200));
  }
  KeyframeSelector selector(smallOptions());
  EXPECT_TRUE(runSelector(selector, 12, [&](int) { return stripes; }).empty());
  ASSERT_FALSE(selector.rejected().empty());
  EXPECT_EQ(selector.rejected().front().reason, "featureless");
  EXPECT_GE(selector.counts().rejected_featureless, 2);  // one per window of 5 frames
}

TEST(KeyframeSelector, ReducedAnalysisResolutionKeepsTheSpacing) {
  // 2x larger frames analysed at half size: the same spacing in full-resolution px.
  const cv::Mat scene = texture(kWidth + kSpeed * 120, kHeight, 6);
  KeyframeOptions options = smallOptions();
  options.analysis_width = kWidth;
  KeyframeSelector selector(options);
  const auto keyframes = runSelector(selector, 70, [&](int i) {
    cv::Mat big;
    cv::resize(panFrame(scene, i), big, cv::Size(), 2, 2, cv::INTER_CUBIC);
    return big;
  });
  ASSERT_GE(keyframes.size(), 3u);
  for (size_t k = 1; k < keyframes.size(); ++k) {
    const int spacing = keyframes[k].frame - keyframes[k - 1].frame;
    EXPECT_GE(spacing, 16);
    EXPECT_LE(spacing, 20);
    EXPECT_NEAR(keyframes[k].motion_px, 2 * kSpeed * spacing, 2.0);
    EXPECT_EQ(keyframes[k].image.cols, 2 * kWidth);  // written at full resolution
  }
}

TEST(KeyframeSelector, BadOptionsAndFramesAreRejectedWithTheirName) {
  KeyframeOptions options;
  options.min_motion = 0;
  try {
    options.check();
    FAIL() << "min_motion = 0 accepted";
  } catch (const OptionError& e) {
    EXPECT_NE(std::string(e.what()).find("min_motion = 0"), std::string::npos) << e.what();
  }
  options = KeyframeOptions();
  options.max_candidate_frames = 2;
  EXPECT_THROW(options.check(), OptionError);
  options = KeyframeOptions();
  options.lk_window = 20;
  EXPECT_THROW(options.check(), OptionError);

  KeyframeSelector selector(smallOptions());
  EXPECT_THROW(selector.addFrame(0, cv::Mat()), std::invalid_argument);
  EXPECT_THROW(selector.addFrame(0, cv::Mat(10, 10, CV_32FC3)), std::invalid_argument);
  selector.addFrame(0, texture(kWidth, kHeight, 1));
  EXPECT_THROW(selector.addFrame(1, texture(kWidth / 2, kHeight, 1)), std::invalid_argument);
}

TEST(FrameTimes, ReadsTheSidecarAndNamesTheBadLine) {
  const fs::path folder = freshFolder("sidecar");
  const fs::path good = folder / "a.mp4.frames.csv";
  std::ofstream(good) << "frame,camera_time_s,sim_time_s\n0,37.4,0.0\n1,37.5,\n";
  const auto times = readFrameTimes(good);
  ASSERT_EQ(times.size(), 2u);
  EXPECT_DOUBLE_EQ(times[1].camera_time_s, 37.5);
  EXPECT_TRUE(times[0].sim_time_s.has_value());
  EXPECT_FALSE(times[1].sim_time_s.has_value());

  const fs::path bad = folder / "b.mp4.frames.csv";
  std::ofstream(bad) << "frame,camera_time_s,sim_time_s\n0,37.4,0.0\n1,abc,0.1\n";
  try {
    readFrameTimes(bad);
    FAIL() << "a bad time was accepted";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("b.mp4.frames.csv:3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("camera_time_s"), std::string::npos) << e.what();
  }
  const fs::path header = folder / "c.mp4.frames.csv";
  std::ofstream(header) << "t,x\n";
  EXPECT_THROW(readFrameTimes(header), StageError);
  // Frame numbers outside size_t were cast to it (undefined; fuzz/regressions/recon_frames/).
  const fs::path order = folder / "d.mp4.frames.csv";
  for (const char* frame : {"-1", "1e300", "-1e300"}) {
    std::ofstream(order) << "frame,camera_time_s,sim_time_s\n0,1,\n" << frame << ",2,\n";
    try {
      readFrameTimes(order);
      FAIL() << "frame " << frame << " was accepted";
    } catch (const StageError& e) {
      EXPECT_NE(std::string(e.what()).find("d.mp4.frames.csv:3: frame " + std::string(frame) +
                                           " out of order (expected 1)"),
                std::string::npos)
          << e.what();
    }
  }
  fs::remove_all(folder);
}

TEST(KeyframeStage, WritesKeyframesIndexAndReport) {
  const fs::path survey = freshFolder("stage");
  writeRecording(survey, "left", 60);
  KeyframesStageOptions options;
  options.selection = smallOptions();
  const KeyframesStageResult result = runKeyframesStage(Survey(survey), options);
  ASSERT_EQ(result.cameras.size(), 1u);
  EXPECT_EQ(result.cameras[0].frames, 60);
  const auto index = readCsv(survey / "keyframes" / "left" / "index.csv");
  ASSERT_GE(index.size(), 4u);  // header + >= 3 keyframes (0, ~16-20, ~32-40, ~48-60)
  EXPECT_EQ(index[0],
            (std::vector<std::string>{"file", "video", "frame", "camera_time_s", "sim_time_s",
                                      "sharpness", "motion_px", "tracked"}));
  int previous = -100;
  for (size_t r = 1; r < index.size(); ++r) {
    ASSERT_EQ(index[r].size(), 8u);
    const int frame = std::stoi(index[r][2]);
    char name[64];
    std::snprintf(name, sizeof(name), "left_0001_%06d.png", frame);
    EXPECT_EQ(index[r][0], name);
    EXPECT_EQ(index[r][1], "left_0001.avi");
    EXPECT_NEAR(std::stod(index[r][3]), 100.0 + 0.1 * frame, 1e-6);  // from the sidecar
    EXPECT_NEAR(std::stod(index[r][4]), 0.1 * frame, 1e-6);
    const cv::Mat png = cv::imread((survey / "keyframes" / "left" / name).string());
    EXPECT_EQ(png.size(), cv::Size(kWidth, kHeight));
    if (r > 1) {
      EXPECT_GE(frame - previous, 16);
      EXPECT_LE(frame - previous, 20);
    }
    previous = frame;
  }
  EXPECT_TRUE(fs::exists(survey / "keyframes" / "left" / "rejected.csv"));
  const nlohmann::json report = readReport(survey / "report.json");
  const auto& left = report["stages"]["keyframes"]["cameras"]["left"];
  EXPECT_EQ(left["frames"], 60);
  EXPECT_EQ(left["keyframes"], static_cast<int>(index.size()) - 1);
  EXPECT_TRUE(left.contains("rejected_blurry"));
  // No staging folders left behind.
  for (const auto& entry : fs::directory_iterator(survey / "keyframes")) {
    EXPECT_NE(entry.path().filename().string()[0], '.') << entry.path();
  }
  fs::remove_all(survey);
}

TEST(KeyframeStage, TruncatedVideoIsAClearErrorAndEarlierKeyframesStay) {
  const fs::path survey = freshFolder("truncated");
  const fs::path video = writeRecording(survey, "left", 60);
  // Earlier output of the stage, which a failing run must leave as it was.
  fs::create_directories(survey / "keyframes" / "left");
  std::ofstream(survey / "keyframes" / "left" / "index.csv") << "earlier\n";
  fs::resize_file(video, fs::file_size(video) / 2);
  KeyframesStageOptions options;
  options.selection = smallOptions();
  try {
    runKeyframesStage(Survey(survey), options);
    FAIL() << "a truncated video was accepted";
  } catch (const StageError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(video.string()), std::string::npos) << message;
  }
  std::ifstream earlier(survey / "keyframes" / "left" / "index.csv");
  std::string line;
  std::getline(earlier, line);
  EXPECT_EQ(line, "earlier");
  EXPECT_EQ(std::distance(fs::directory_iterator(survey / "keyframes"), fs::directory_iterator()),
            1);  // no staging folder left

  // --keep-damaged: the keyframes before the damage are kept, the problem reported.
  options.video.keep_damaged = true;
  const KeyframesStageResult result = runKeyframesStage(Survey(survey), options);
  ASSERT_EQ(result.problems.size(), 1u);
  EXPECT_NE(result.problems[0].find("truncated"), std::string::npos) << result.problems[0];
  EXPECT_LT(result.cameras[0].frames, 60);
  EXPECT_GE(result.cameras[0].keyframes, 1);
  const nlohmann::json report = readReport(survey / "report.json");
  EXPECT_EQ(report["stages"]["keyframes"]["problems"].size(), 1u);
  fs::remove_all(survey);
}

TEST(KeyframeStage, GarbageVideoAndMismatchedSidecarAreClearErrors) {
  const fs::path survey = freshFolder("garbage");
  fs::create_directories(survey / "recordings" / "left");
  const fs::path garbage = survey / "recordings" / "left" / "left_0001.mp4";
  std::ofstream(garbage) << std::string(5000, 'x');
  KeyframesStageOptions options;
  try {
    runKeyframesStage(Survey(survey), options);
    FAIL() << "garbage accepted";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find(garbage.string()), std::string::npos) << e.what();
  }
  fs::remove(garbage);
  // A sidecar listing fewer frames than the video holds: not this video's sidecar.
  const fs::path video = writeRecording(survey, "left", 30, "avi", 10);
  options.selection = smallOptions();
  try {
    runKeyframesStage(Survey(survey), options);
    FAIL() << "a mismatched sidecar was accepted";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("sidecar"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(survey / "keyframes" / "left"));
  fs::remove_all(survey);
}

TEST(KeyframeStage, EmptyOrMissingFoldersAreClearErrors) {
  const fs::path survey = freshFolder("empty");
  KeyframesStageOptions options;
  EXPECT_THROW(runKeyframesStage(Survey(survey), options), StageError);  // no recordings/
  fs::create_directories(survey / "recordings" / "left");
  try {
    runKeyframesStage(Survey(survey), options);
    FAIL() << "an empty camera folder was accepted";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("no videos"), std::string::npos) << e.what();
  }
  options.cameras = {"forward"};
  try {
    runKeyframesStage(Survey(survey), options);
    FAIL() << "a missing camera was accepted";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("forward"), std::string::npos) << e.what();
  }
  fs::remove_all(survey);
}

TEST(KeyframeCommand, ExitCodesAndMessages) {
  const fs::path survey = freshFolder("command");
  std::string err;
  EXPECT_EQ(runTool("keyframes " + survey.string(), &err), 1);
  EXPECT_NE(err.find("recordings"), std::string::npos) << err;
  EXPECT_EQ(runTool("keyframes " + survey.string() + " --min-motion 2", &err), 2);
  EXPECT_NE(err.find("min_motion = 2"), std::string::npos) << err;
  writeRecording(survey, "left", 40);
  EXPECT_EQ(runTool("keyframes " + survey.string() + " --analysis-width 0", &err), 0) << err;
  EXPECT_TRUE(fs::exists(survey / "keyframes" / "left" / "index.csv"));
  fs::remove_all(survey);
}

TEST(KeyframesStageOptions, BindTakesFlagsAndTheConfigSection) {
  const fs::path folder = freshFolder("bind");
  std::ofstream(folder / "recon.yaml")
      << "keyframes:\n  lk_levels: 2\n  camera: [left, right]\n  keep_damaged: true\n"
         "dense:\n  max_image_size: 512\n";  // other sections are not this stage's business
  KeyframesStageOptions options;
  OptionSet set("keyframes");
  options.bind(set);
  // Flags win over the file wherever --config stands.
  ASSERT_TRUE(set.parse({"--min-motion", "0.2", "--config", (folder / "recon.yaml").string(),
                         "--lk_levels", "4", "--png-compression", "3"}));
  EXPECT_DOUBLE_EQ(options.selection.min_motion, 0.2);
  EXPECT_EQ(options.selection.lk_levels, 4);
  EXPECT_EQ(options.video.png_compression, 3);
  EXPECT_EQ(options.cameras, (std::vector<std::string>{"left", "right"}));
  EXPECT_TRUE(options.video.keep_damaged);
  EXPECT_EQ(options.selection.max_features, KeyframeOptions().max_features);  // default kept
  EXPECT_NO_THROW(options.check());
  // An unknown key of the section names the file and the key.
  std::ofstream(folder / "recon.yaml") << "keyframes:\n  min_motion_px: 40\n";
  try {
    set.applyConfigFile(folder / "recon.yaml");
    FAIL() << "an unknown key was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("keyframes.min_motion_px"), std::string::npos) << e.what();
  }
  fs::remove_all(folder);
}
