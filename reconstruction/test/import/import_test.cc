// `auv recon import`: EXIF read by libexiv2 from files it wrote (and from real camera photos),
// orientation, intrinsics priors and their safeguards, camera groups, skipped files, the
// survey left intact on refusal, videos with their sidecars, and the command's exit codes.

#include <sys/wait.h>
#include <unistd.h>

#include <exiv2/exiv2.hpp>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "auv/recon/common/report.h"
#include "auv/recon/common/stage_error.h"
#include "auv/recon/import/exif.h"
#include "auv/recon/import/import_stage.h"
#include "auv/recon/import/intrinsics_prior.h"
#include "auv/recon/import/photos.h"

namespace fs = std::filesystem;
using namespace auv::recon;
using namespace auv::recon::import;

namespace {

fs::path freshFolder(const std::string& name) {
  const fs::path folder =
      fs::temp_directory_path() / ("auv_recon_import_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

// A textured image whose top-left 8x8 block is pure red (to follow orientation).
cv::Mat marked(int width, int height, unsigned seed) {
  cv::Mat image(height, width, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 200);
  image(cv::Rect(0, 0, 8, 8)).setTo(cv::Scalar(0, 0, 255));
  return image;
}

// Writes a JPEG and then EXIF with libexiv2 (keys as in the EXIF spec; values as strings).
void writeJpeg(const fs::path& file, const cv::Mat& image,
               const std::vector<std::pair<std::string, std::string>>& exif = {}) {
  ASSERT_TRUE(cv::imwrite(file.string(), image, {cv::IMWRITE_JPEG_QUALITY, 95}));
  if (exif.empty()) return;
  auto handle = Exiv2::ImageFactory::open(file.string());
  handle->readMetadata();
  Exiv2::ExifData& data = handle->exifData();
  for (const auto& [key, value] : exif) data[key] = value;
  handle->writeMetadata();
}

std::vector<unsigned char> bytesOf(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string textOf(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

bool isRed(const cv::Vec3b& bgr) { return bgr[2] > 200 && bgr[0] < 60 && bgr[1] < 60; }

int runTool(const std::string& arguments, std::string* err) {
  const fs::path log =
      fs::temp_directory_path() / ("auv_recon_import_stderr_" + std::to_string(::getpid()));
  const std::string command =
      std::string(AUV_RECON_TOOL) + " " + arguments + " >/dev/null 2>" + log.string();
  const int status = std::system(command.c_str());
  *err = textOf(log);
  fs::remove(log);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

TEST(Exif, ReadsWhatLibexiv2Wrote) {
  const fs::path folder = freshFolder("exif");
  writeJpeg(folder / "a.jpg", marked(64, 48, 1),
            {{"Exif.Image.Orientation", "6"},
             {"Exif.Image.Make", "ACME"},
             {"Exif.Image.Model", "ACME Diver 3"},
             {"Exif.Photo.FocalLength", "47/10"},
             {"Exif.Photo.FocalLengthIn35mmFilm", "26"},
             {"Exif.Photo.FocalPlaneXResolution", "2000/1"},
             {"Exif.Photo.FocalPlaneResolutionUnit", "3"},
             {"Exif.Photo.PixelXDimension", "4000"},
             {"Exif.Photo.PixelYDimension", "3000"},
             {"Exif.Photo.DateTimeOriginal", "2024:06:01 10:00:05"},
             {"Exif.Photo.SubSecTimeOriginal", "25"}});
  const ExifInfo info = readExif(bytesOf(folder / "a.jpg"));
  EXPECT_EQ(info.orientation, 6);
  EXPECT_EQ(info.make, "ACME");
  EXPECT_EQ(info.model, "ACME Diver 3");
  ASSERT_TRUE(info.focal_mm && info.focal_35mm && info.focal_plane_x_per_mm);
  EXPECT_DOUBLE_EQ(*info.focal_mm, 4.7);
  EXPECT_DOUBLE_EQ(*info.focal_35mm, 26.0);
  EXPECT_DOUBLE_EQ(*info.focal_plane_x_per_mm, 200.0);  // 2000 px per cm
  ASSERT_TRUE(info.pixel_dimensions);
  EXPECT_EQ(*info.pixel_dimensions, cv::Size(4000, 3000));
  ASSERT_TRUE(info.time_s);
  EXPECT_DOUBLE_EQ(*info.time_s, 1717236005.25);  // 2024-06-01T10:00:05.25 read as UTC
  EXPECT_TRUE(info.ignored.empty());

  // No EXIF at all, and bytes that are not an image: the defaults, no exception.
  cv::imwrite((folder / "plain.png").string(), marked(16, 16, 2));
  const ExifInfo none = readExif(bytesOf(folder / "plain.png"));
  EXPECT_EQ(none.orientation, 1);
  EXPECT_FALSE(none.focal_mm || none.focal_35mm || none.time_s);
  EXPECT_EQ(readExif({'n', 'o', 't'}).orientation, 1);
  fs::remove_all(folder);
}

TEST(Exif, OrientationTurnsTheImageUpright) {
  // Stored 40x20 with the mark at the stored top-left; where the mark lands once upright.
  const cv::Mat stored = marked(40, 20, 3);
  struct Case {
    int orientation;
    cv::Size size;
    cv::Point mark;  // a pixel inside the mark, upright
  };
  const std::vector<Case> cases = {{1, {40, 20}, {1, 1}},   {2, {40, 20}, {38, 1}},
                                   {3, {40, 20}, {38, 18}}, {4, {40, 20}, {1, 18}},
                                   {5, {20, 40}, {1, 1}},   {6, {20, 40}, {18, 1}},
                                   {7, {20, 40}, {18, 38}}, {8, {20, 40}, {1, 38}}};
  for (const Case& c : cases) {
    const cv::Mat upright = applyOrientation(stored, c.orientation);
    EXPECT_EQ(upright.size(), c.size) << "orientation " << c.orientation;
    EXPECT_TRUE(isRed(upright.at<cv::Vec3b>(c.mark))) << "orientation " << c.orientation;
  }
}

TEST(IntrinsicsPrior, FromStatementExifOrDefaultAndLiesIgnored) {
  const cv::Size size(4000, 3000);  // diagonal 5000 px
  PriorOptions options;
  ExifInfo exif;
  exif.focal_35mm = 26.0;
  exif.focal_mm = 4.7;
  exif.focal_plane_x_per_mm = 800.0;
  IntrinsicsPrior p = intrinsicsPrior(exif, size, options);
  EXPECT_EQ(p.source, "exif_35mm");
  EXPECT_NEAR(p.focal_px, 26.0 * 5000.0 / 43.266615, 1e-6);
  EXPECT_DOUBLE_EQ(p.cx, 1999.5);
  EXPECT_DOUBLE_EQ(p.cy, 1499.5);

  exif.focal_35mm.reset();
  p = intrinsicsPrior(exif, size, options);
  EXPECT_EQ(p.source, "exif_focal_plane");
  EXPECT_NEAR(p.focal_px, 4.7 * 800.0, 1e-9);
  exif.pixel_dimensions = cv::Size(8000, 6000);  // saved at half size
  EXPECT_NEAR(intrinsicsPrior(exif, size, options).focal_px, 0.5 * 4.7 * 800.0, 1e-9);

  // A 35 mm equivalent of 1 mm (a 180-degree view) and a focal-plane focal of 0.05 px are lies.
  exif = ExifInfo{};
  exif.focal_35mm = 1.0;
  exif.focal_mm = 0.001;
  exif.focal_plane_x_per_mm = 50.0;
  p = intrinsicsPrior(exif, size, options);
  EXPECT_EQ(p.source, "default");
  EXPECT_DOUBLE_EQ(p.focal_px, 1.2 * 4000.0);
  ASSERT_EQ(p.ignored.size(), 2u);
  EXPECT_NE(p.ignored[0].find("FocalLengthIn35mmFilm"), std::string::npos);

  // A statement wins over EXIF; both at once is refused.
  options.focal_px = 3100.0;
  EXPECT_EQ(intrinsicsPrior(exif, size, options).source, "stated_focal_px");
  options.focal_35mm = 28.0;
  EXPECT_THROW(options.check(), std::invalid_argument);
}

TEST(Photos, DamagedFilesAreNamedAndTheRestDecode) {
  const fs::path folder = freshFolder("damage");
  writeJpeg(folder / "good.jpg", marked(64, 48, 4));
  std::vector<unsigned char> jpeg = bytesOf(folder / "good.jpg");
  EXPECT_EQ(photoDamage(jpeg, nullptr), "");
  jpeg.resize(jpeg.size() * 2 / 3);
  EXPECT_NE(photoDamage(jpeg, nullptr).find("truncated JPEG"), std::string::npos);
  cv::imwrite((folder / "good.png").string(), marked(64, 48, 5));
  std::vector<unsigned char> png = bytesOf(folder / "good.png");
  EXPECT_EQ(photoDamage(png, nullptr), "");
  png.resize(png.size() / 2);
  EXPECT_NE(photoDamage(png, nullptr).find("truncated PNG"), std::string::npos);
  EXPECT_NE(photoDamage({'h', 'e', 'l', 'l', 'o'}, nullptr).find("not a readable image"),
            std::string::npos);
  EXPECT_EQ(photoDamage({}, nullptr), "empty file");
  fs::remove_all(folder);
}

TEST(ImportStage, PhotosLandUprightInOneCameraPerGroupAndBadFilesAreSkipped) {
  const fs::path root = freshFolder("photos");
  const fs::path photos = root / "dive_42";
  fs::create_directories(photos);
  const std::vector<std::pair<std::string, std::string>> phone = {
      {"Exif.Image.Model", "Phone X"},
      {"Exif.Photo.FocalLength", "4/1"},
      {"Exif.Photo.FocalLengthIn35mmFilm", "28"},
      {"Exif.Photo.DateTimeOriginal", "2024:06:01 10:00:00"}};
  auto turned = phone;
  turned.push_back({"Exif.Image.Orientation", "6"});
  writeJpeg(photos / "p1.jpg", marked(80, 60, 6), phone);
  writeJpeg(photos / "p2.JPG", marked(80, 60, 7), phone);
  writeJpeg(photos / "p3.jpg", marked(60, 80, 8).t(), turned);  // stored 80x60, held upright
  writeJpeg(photos / "other.jpg", marked(100, 50, 9));          // another camera: no EXIF
  std::vector<unsigned char> cut = bytesOf(photos / "p1.jpg");
  cut.resize(cut.size() / 2);
  std::ofstream(photos / "cut.jpg", std::ios::binary)
      .write(reinterpret_cast<const char*>(cut.data()), static_cast<long>(cut.size()));
  std::ofstream(photos / "notes.jpg") << "not a photo";
  std::ofstream(photos / "readme.txt") << "ignored: not an image extension";

  const Survey survey(root / "survey");
  ImportStageOptions options;
  options.images = photos.string();
  const ImportStageResult result = runImportStage(survey, options);

  ASSERT_EQ(result.cameras.size(), 3u);  // 80x60 Phone X, 60x80 Phone X, 100x50 no EXIF
  EXPECT_EQ(result.cameras[0].camera, "dive_42");
  EXPECT_EQ(result.cameras[0].images, 2);
  EXPECT_EQ(result.cameras[0].with_time, 2);
  EXPECT_EQ(result.cameras[0].prior.source, "exif_35mm");
  ASSERT_EQ(result.skipped.size(), 2u);
  EXPECT_NE(result.skipped[0].file.find("cut.jpg"), std::string::npos);
  EXPECT_NE(result.skipped[0].reason.find("truncated"), std::string::npos);
  EXPECT_NE(result.skipped[1].file.find("notes.jpg"), std::string::npos);

  const fs::path main_camera = survey.keyframes() / "dive_42";
  EXPECT_TRUE(fs::exists(main_camera / "p1.png"));
  EXPECT_TRUE(fs::exists(main_camera / "p2.png"));
  const std::string index = textOf(main_camera / "index.csv");
  EXPECT_EQ(index.rfind("file,source,camera_time_s,sim_time_s,orientation,width,height\n", 0), 0u);
  EXPECT_NE(index.find("p1.png,p1.jpg,1717236000,,1,80,60"), std::string::npos);

  // The photo held upright: 60x80 in its own camera, its mark at the upright top-left.
  bool found_turned = false, found_other = false;
  for (const ImportedCamera& c : result.cameras) {
    if (fs::exists(survey.keyframes() / c.camera / "p3.png")) {
      found_turned = true;
      EXPECT_EQ(c.upright_turned, 1);
      const cv::Mat upright = cv::imread((survey.keyframes() / c.camera / "p3.png").string());
      EXPECT_EQ(upright.size(), cv::Size(60, 80));
      EXPECT_TRUE(
          isRed(upright.at<cv::Vec3b>(2, 57)));  // orientation 6: stored top-left -> top-right
    }
    if (fs::exists(survey.keyframes() / c.camera / "other.png")) {
      found_other = true;
      EXPECT_EQ(c.prior.source, "default");
      EXPECT_DOUBLE_EQ(c.prior.focal_px, 120.0);
    }
    EXPECT_TRUE(fs::exists(survey.calibration() / (c.camera + ".prior.yaml")));
    const IntrinsicsPrior read =
        readIntrinsicsPrior(survey.calibration() / (c.camera + ".prior.yaml"), "test");
    EXPECT_NEAR(read.focal_px, c.prior.focal_px, 1e-6);
  }
  EXPECT_TRUE(found_turned && found_other);
  const nlohmann::json report = readReport(survey.report());
  EXPECT_EQ(report["stages"]["import"]["cameras"]["dive_42"]["images"], 2);
  EXPECT_EQ(report["stages"]["import"]["last_run"]["skipped"].size(), 2u);
  fs::remove_all(root);
}

TEST(ImportStage, CameraIdsFromNamesAreFolderNamesAndCsvFields) {
  EXPECT_EQ(cameraIdFrom("dive_42"), "dive_42");
  EXPECT_EQ(cameraIdFrom("reef, north"), "reef_ north");
  EXPECT_EQ(cameraIdFrom(".hidden"), "_hidden");
  EXPECT_EQ(cameraIdFrom(""), "camera");
}

TEST(ImportStage, RefusesToOverwriteAndLeavesTheSurveyAsItWas) {
  const fs::path root = freshFolder("refuse");
  fs::create_directories(root / "a");
  writeJpeg(root / "a" / "x.jpg", marked(64, 48, 10));
  const Survey survey(root / "survey");
  ImportStageOptions options;
  options.images = (root / "a").string();
  options.camera = "cam";
  runImportStage(survey, options);
  const auto before = fs::last_write_time(survey.keyframes() / "cam" / "x.png");

  fs::create_directories(root / "b");
  writeJpeg(root / "b" / "y.jpg", marked(64, 48, 11));
  options.images = (root / "b").string();
  try {
    runImportStage(survey, options);
    FAIL() << "expected a refusal";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("already exists"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::exists(survey.keyframes() / "cam" / "x.png"));
  EXPECT_EQ(fs::last_write_time(survey.keyframes() / "cam" / "x.png"), before);
  EXPECT_FALSE(fs::exists(survey.keyframes() / "cam" / "y.png"));

  // Nothing readable: refused, the earlier import intact.
  fs::create_directories(root / "c");
  std::ofstream(root / "c" / "z.jpg") << "garbage";
  options.images = (root / "c").string();
  options.camera = "cam2";
  EXPECT_THROW(runImportStage(survey, options), StageError);
  EXPECT_FALSE(fs::exists(survey.keyframes() / "cam2"));
  EXPECT_TRUE(fs::exists(survey.keyframes() / "cam" / "x.png"));

  options.images = (root / "b").string();
  options.camera = "cam";
  options.replace = true;
  runImportStage(survey, options);
  EXPECT_TRUE(fs::exists(survey.keyframes() / "cam" / "y.png"));
  EXPECT_FALSE(fs::exists(survey.keyframes() / "cam" / "x.png"));
  fs::remove_all(root);
}

TEST(ImportStage, VideoLandsInRecordingsWithItsSidecar) {
  const fs::path root = freshFolder("video");
  const fs::path video = root / "pool.avi";
  {
    cv::VideoWriter writer(video.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0,
                           cv::Size(64, 48));
    ASSERT_TRUE(writer.isOpened());
    for (int i = 0; i < 12; ++i) writer.write(marked(64, 48, 20 + i));
  }
  const Survey survey(root / "survey");
  ImportStageOptions options;
  options.video = video.string();
  options.camera = "rov";
  options.prior.focal_35mm = 20.0;
  const ImportStageResult result = runImportStage(survey, options);
  ASSERT_EQ(result.cameras.size(), 1u);
  EXPECT_EQ(result.cameras[0].frames, 12);
  EXPECT_EQ(result.cameras[0].prior.source, "stated_35mm");
  const fs::path copy = survey.recordings() / "rov" / "pool.avi";
  EXPECT_EQ(fs::file_size(copy), fs::file_size(video));
  std::istringstream sidecar(textOf(copy.string() + ".frames.csv"));
  std::string line;
  std::getline(sidecar, line);
  EXPECT_EQ(line, "frame,camera_time_s,sim_time_s");
  int rows = 0;
  while (std::getline(sidecar, line)) {
    if (rows == 11) {
      EXPECT_EQ(line, "11,1.1,") << "10 Hz container times";
    }
    ++rows;
  }
  EXPECT_EQ(rows, 12);

  // The same name again is refused; another size in the same camera is refused.
  EXPECT_THROW(runImportStage(survey, options), StageError);
  const fs::path wide = root / "wide.avi";
  {
    cv::VideoWriter writer(wide.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0,
                           cv::Size(96, 48));
    for (int i = 0; i < 3; ++i) writer.write(marked(96, 48, 40 + i));
  }
  options.video = wide.string();
  try {
    runImportStage(survey, options);
    FAIL() << "expected a refusal";
  } catch (const StageError& e) {
    EXPECT_NE(std::string(e.what()).find("96x48"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(survey.recordings() / "rov" / "wide.avi"));

  // Not a video.
  std::ofstream(root / "fake.mp4") << "not a video";
  options.video = (root / "fake.mp4").string();
  options.camera = "other";
  EXPECT_THROW(runImportStage(survey, options), StageError);
  EXPECT_FALSE(fs::exists(survey.recordings() / "other" / "fake.mp4"));
  fs::remove_all(root);
}

TEST(ImportStage, RealCameraPhotosGiveAPriorNearTheKnownFocal) {
  const fs::path images = fs::path(AUV_RECON_SHARED_DATA) / "sceaux_castle" / "images";
  if (!fs::is_directory(images)) {
    GTEST_SKIP() << images << " not found: the Sceaux castle photos (../shared/data) are absent";
  }
  const fs::path root = freshFolder("sceaux");
  const Survey survey(root / "survey");
  ImportStageOptions options;
  options.images = images.string();
  const ImportStageResult result = runImportStage(survey, options);
  ASSERT_EQ(result.cameras.size(), 1u);
  EXPECT_EQ(result.cameras[0].camera, "images");
  EXPECT_EQ(result.cameras[0].images, 11);
  EXPECT_EQ(result.cameras[0].with_time, 11);
  EXPECT_EQ(result.cameras[0].group,
            "2832x2128 EASTMAN KODAK COMPANY KODAK Z612 ZOOM DIGITAL CAMERA, 5.85 mm");
  // The Kodak writes a 35 mm equivalent of 35 mm; images/K.txt says fx = 2905.88 px.
  EXPECT_EQ(result.cameras[0].prior.source, "exif_35mm");
  EXPECT_NEAR(result.cameras[0].prior.focal_px / 2905.88, 1.0, 0.02);
  EXPECT_TRUE(result.skipped.empty());
  fs::remove_all(root);
}

TEST(ImportCommand, ExitCodes) {
  const fs::path root = freshFolder("tool");
  std::string err;
  EXPECT_EQ(runTool("import " + (root / "s").string(), &err), 2) << err;
  EXPECT_NE(err.find("--images"), std::string::npos) << err;
  EXPECT_EQ(runTool("import " + (root / "s").string() + " --images x --video y", &err), 2);
  EXPECT_EQ(
      runTool("import " + (root / "s").string() + " --images " + (root / "none").string(), &err),
      1);
  EXPECT_NE(err.find("no such folder"), std::string::npos) << err;
  fs::create_directories(root / "p");
  writeJpeg(root / "p" / "a.jpg", marked(64, 48, 50));
  std::ofstream(root / "p" / "b.jpg") << "garbage";
  EXPECT_EQ(runTool("import " + (root / "s").string() + " --images " + (root / "p").string(), &err),
            0)
      << err;
  EXPECT_NE(err.find("b.jpg: skipped"), std::string::npos) << err;
  fs::remove_all(root);
}
