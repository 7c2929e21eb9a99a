#pragma once
// What a photo's EXIF says that a reconstruction can use, read with libexiv2: how the camera
// was held (Orientation), the lens (focal length, its 35 mm equivalent, the focal-plane
// resolution that gives the sensor's size), which camera (Make, Model) and when
// (DateTimeOriginal). Every field is optional: phones, cameras and frame grabbers write
// different subsets, and stripped files write none.

#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace auv::recon::import {

struct ExifInfo {
  int orientation = 1;             ///< EXIF Orientation 1-8 (1: as stored); other values read as 1
  std::optional<double> focal_mm;  ///< Exif.Photo.FocalLength
  std::optional<double> focal_35mm;            ///< Exif.Photo.FocalLengthIn35mmFilm
  std::optional<double> focal_plane_x_per_mm;  ///< pixels per mm on the sensor (FocalPlane*)
  std::optional<cv::Size> pixel_dimensions;    ///< Exif.Photo.PixelX/YDimension, as stored
  std::string make, model;
  std::optional<double> time_s;  ///< DateTimeOriginal (+ SubSecTimeOriginal), s since 1970 UTC*
  /// Fields present but unusable, for the import's report ("FocalLength = 0").
  std::vector<std::string> ignored;
  // * EXIF times carry no time zone: they are read as UTC, which keeps their differences right.
};

/// Reads the EXIF of an encoded image (JPEG, PNG, TIFF, WebP, ...). A file without EXIF, or one
/// libexiv2 cannot parse, gives the defaults: EXIF is a hint, never a reason to refuse an image.
ExifInfo readExif(const std::vector<unsigned char>& encoded);

/// The image turned upright as EXIF `orientation` says (1-8: rotations and mirror images).
cv::Mat applyOrientation(const cv::Mat& stored, int orientation);

}  // namespace auv::recon::import
