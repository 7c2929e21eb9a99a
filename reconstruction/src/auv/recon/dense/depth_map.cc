#include "auv/recon/dense/depth_map.h"

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "auv/recon/common/staged_output.h"

namespace auv::recon::dense {

void writeDenseArray(const std::filesystem::path& file, const cv::Mat& image) {
  if (image.depth() != CV_32F || (image.channels() != 1 && image.channels() != 3)) {
    throw std::invalid_argument("dense: " + file.string() +
                                ": only CV_32FC1 / CV_32FC3 arrays can be written");
  }
  std::ostringstream out;
  out << image.cols << "&" << image.rows << "&" << image.channels() << "&";
  std::vector<cv::Mat> planes;
  cv::split(image, planes);
  for (const cv::Mat& plane : planes) {
    const cv::Mat contiguous = plane.isContinuous() ? plane : plane.clone();
    out.write(reinterpret_cast<const char*>(contiguous.ptr<float>()),
              static_cast<std::streamsize>(contiguous.total() * sizeof(float)));
  }
  writeFileAtomically(file, out.str());
}

cv::Mat readDenseArray(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("dense: cannot open " + file.string());
  int size[3] = {0, 0, 0};
  for (int& value : size) {
    std::string text;
    if (!std::getline(in, text, '&')) {
      throw std::runtime_error("dense: " + file.string() + ": malformed header");
    }
    try {
      size_t used = 0;
      value = std::stoi(text, &used);
      if (used != text.size()) throw std::invalid_argument(text);
    } catch (const std::exception&) {
      throw std::runtime_error("dense: " + file.string() + ": malformed header field '" + text +
                               "'");
    }
  }
  const int width = size[0], height = size[1], channels = size[2];
  if (width <= 0 || height <= 0 || (channels != 1 && channels != 3) || width > 100000 ||
      height > 100000) {
    throw std::runtime_error("dense: " + file.string() + ": bad size " + std::to_string(width) +
                             "x" + std::to_string(height) + "x" + std::to_string(channels));
  }
  std::vector<cv::Mat> planes;
  for (int c = 0; c < channels; ++c) {
    cv::Mat plane(height, width, CV_32F);
    in.read(reinterpret_cast<char*>(plane.ptr<float>()),
            static_cast<std::streamsize>(plane.total() * sizeof(float)));
    if (!in) throw std::runtime_error("dense: " + file.string() + ": truncated");
    planes.push_back(plane);
  }
  cv::Mat image;
  cv::merge(planes, image);
  return image;
}

cv::Mat normalsFromDepth(const cv::Mat& depth, const View& view, int step) {
  CV_Assert(depth.type() == CV_32F && step >= 1);
  cv::Mat normals(depth.size(), CV_32FC3, cv::Scalar::all(0));
  const double fx = view.K(0, 0), fy = view.K(1, 1), cx = view.K(0, 2), cy = view.K(1, 2);
  const Eigen::Matrix3d to_world = view.R.transpose();
  const auto point = [&](int x, int y) {
    const double d = depth.at<float>(y, x);
    return Eigen::Vector3d((x - cx) / fx * d, (y - cy) / fy * d, d);
  };
  const auto valid = [&](int x, int y) {
    return x >= 0 && y >= 0 && x < depth.cols && y < depth.rows && depth.at<float>(y, x) > 0;
  };
  for (int y = 0; y < depth.rows; ++y) {
    for (int x = 0; x < depth.cols; ++x) {
      if (!valid(x, y)) continue;
      const Eigen::Vector3d centre = point(x, y);
      Eigen::Vector3d axis[2];
      bool ok = true;
      for (int a = 0; a < 2 && ok; ++a) {
        const int dx = a == 0 ? step : 0, dy = a == 0 ? 0 : step;
        const bool plus = valid(x + dx, y + dy), minus = valid(x - dx, y - dy);
        if (plus && minus) {
          axis[a] = point(x + dx, y + dy) - point(x - dx, y - dy);
        } else if (plus) {
          axis[a] = point(x + dx, y + dy) - centre;
        } else if (minus) {
          axis[a] = centre - point(x - dx, y - dy);
        } else {
          ok = false;
        }
      }
      if (!ok) continue;
      Eigen::Vector3d normal = axis[0].cross(axis[1]);
      const double norm = normal.norm();
      if (norm <= 0) continue;
      normal /= norm;
      if (normal.dot(centre) > 0) normal = -normal;  // towards the camera
      const Eigen::Vector3d world = to_world * normal;
      normals.at<cv::Vec3f>(y, x) =
          cv::Vec3f(static_cast<float>(world.x()), static_cast<float>(world.y()),
                    static_cast<float>(world.z()));
    }
  }
  return normals;
}

}  // namespace auv::recon::dense
