// Texturing a synthetic sea floor surveyed in a lawnmower pattern (images on disk, read through
// the stage's image cache): time per step beside two anchors measured in the same run — reading
// every image once (the I/O floor) and the greedy labelling — and texture fidelity (PSNR of
// held-out views re-rendered from the model against the true texture) with the MRF and greedy.
//
//   texture_bench [--grid 120] [--views 30] [--width 1352] [--height 1014] [--out bench_results]
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "../../test/texture/synthetic_scene.h"
#include "auv/recon/texture/image_cache.h"
#include "auv/recon/texture/texturer.h"

namespace fs = std::filesystem;
using namespace auv::recon::texture;

namespace {
double seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}
}  // namespace

int main(int argc, char** argv) {
  int grid = 120, num_views = 30, width = 1352, height = 1014;
  std::string out = "bench_results";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--grid")
      grid = std::stoi(argv[i + 1]);
    else if (flag == "--views")
      num_views = std::stoi(argv[i + 1]);
    else if (flag == "--width")
      width = std::stoi(argv[i + 1]);
    else if (flag == "--height")
      height = std::stoi(argv[i + 1]);
    else if (flag == "--out")
      out = argv[i + 1];
    else {
      std::cerr
          << "usage: texture_bench [--grid N] [--views N] [--width W] [--height H] [--out DIR]\n";
      return 2;
    }
  }
  const double focal = 0.74 * width;  // GoPro-like 68 deg horizontal field of view
  const synth::Height terrain = [](double x, double y) {
    return 0.15 * std::sin(1.3 * x) * std::cos(1.1 * y) +
           0.6 * std::exp(-((x - 0.8) * (x - 0.8) + (y + 0.5) * (y + 0.5)) / 0.18);
  };
  const FaceMesh mesh = synth::gridMesh(grid, 2.0, terrain);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> jitter(-0.15, 0.15), gain(0.85, 1.15);
  const fs::path folder =
      fs::temp_directory_path() / ("texture_bench_" + std::to_string(::getpid()));
  fs::create_directories(folder);

  // Lawnmower: rows along x at 2 m altitude, cameras tilted a little along the track.
  std::vector<ViewGeometry> views;
  std::vector<fs::path> files;
  std::vector<cv::Size> sizes;
  const int rows = std::max(1, static_cast<int>(std::round(std::sqrt(num_views / 1.5))));
  const int per_row = (num_views + rows - 1) / rows;
  auto start = std::chrono::steady_clock::now();
  for (int v = 0; v < num_views; ++v) {
    const int r = v / per_row, k = v % per_row;
    const double y = rows == 1 ? 0 : -1.5 + 3.0 * r / (rows - 1);
    const double x = per_row == 1 ? 0 : -1.6 + 3.2 * (r % 2 ? per_row - 1 - k : k) / (per_row - 1);
    const Eigen::Vector3d center(x + jitter(rng), y + jitter(rng), 2.0 + jitter(rng));
    views.push_back(
        synth::lookAt(center, Eigen::Vector3d(x + 0.3 * jitter(rng), y, 0), width, height, focal));
    files.push_back(folder / ("view_" + std::to_string(v) + ".png"));
    sizes.emplace_back(width, height);
    cv::imwrite(files.back().string(),
                synth::renderTruth(mesh, views.back(), gain(rng), {}, 2.0, v + 1));
  }
  const double render_s = seconds(start);

  // Anchor 1: reading every image once.
  start = std::chrono::steady_clock::now();
  for (const auto& file : files) cv::imread(file.string(), cv::IMREAD_COLOR);
  const double read_s = seconds(start);

  std::vector<ViewGeometry> held_out;
  for (const Eigen::Vector3d& c : {Eigen::Vector3d(-0.5, 0.3, 1.6), Eigen::Vector3d(0.9, -0.6, 1.8),
                                   Eigen::Vector3d(0.2, 1.0, 2.2)}) {
    held_out.push_back(
        synth::lookAt(c, Eigen::Vector3d(c.x() * 0.8, c.y() * 0.8, 0), width, height, focal));
  }
  std::ostringstream report;
  report << "# texture_bench: " << mesh.faces.size() << " faces, " << num_views << " views "
         << width << "x" << height << " (PNG on disk, rendered in " << render_s
         << " s), 2-core machine shared with other builds: timings are noisy\n\n"
         << "Anchor: reading the " << num_views << " images once: " << read_s << " s\n\n"
         << "| labelling | visibility s | selection s | levelling s | atlas s | total s | "
            "energy | seams | patches | pages | held-out PSNR dB (3 views) | peak RSS MB |\n"
         << "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const bool mrf : {false, true}) {
    ImageCache cache(files, sizes, 24);
    const ImageLoader loader = [&cache](int v) { return cv::Mat(cache.get(v)); };
    TextureOptions options;
    options.selection.use_mrf = mrf;
    start = std::chrono::steady_clock::now();
    const TextureResult result = textureMesh(mesh, views, loader, options);
    const double total = seconds(start);
    std::ostringstream psnrs;
    for (const ViewGeometry& view : held_out) {
      const Rendering rendering = renderTexturedModel(result.model, view);
      psnrs << (psnrs.tellp() > 0 ? " / " : "")
            << cv::format("%.1f",
                          psnr(rendering.image, synth::renderTruth(mesh, view), rendering.mask));
    }
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    const TextureStats& s = result.stats;
    report << "| " << (mrf ? "MRF (alpha-expansion)" : "greedy (anchor)") << " | "
           << s.seconds_visibility << " | " << s.seconds_selection << " | " << s.seconds_leveling
           << " | " << s.seconds_atlas << " | " << total << " | " << s.energy << " | " << s.seams
           << " | " << s.atlas.patches << " | " << s.atlas.pages << " x " << s.atlas.page_size
           << " | " << psnrs.str() << " | " << usage.ru_maxrss / 1024 << " |\n";
  }
  report << "\nHeld-out PSNR is against the true texture; the survey images carry random "
            "exposure gains 0.85-1.15 and noise sigma 2, so a perfect model cannot reach the "
            "PSNR of an exact copy.\n";
  fs::remove_all(folder);
  std::cout << report.str();
  fs::create_directories(out);
  char stamp[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(stamp, sizeof(stamp), "%Y%m%d_%H%M%S", std::localtime(&now));
  const fs::path file = fs::path(out) / ("texture_bench_" + std::string(stamp) + ".md");
  std::ofstream(file) << report.str();
  std::cout << "-> " << file.string() << std::endl;
  return 0;
}
