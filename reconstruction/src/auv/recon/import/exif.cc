#include "auv/recon/import/exif.h"

#include <cmath>
#include <ctime>
#include <exiv2/exiv2.hpp>
#include <mutex>
#include <opencv2/core.hpp>

namespace auv::recon::import {
namespace {

// A positive number, or nothing; a value that is there but not positive is noted in `ignored`.
std::optional<double> positiveNumber(const Exiv2::ExifData& exif, const char* key,
                                     std::vector<std::string>& ignored) {
  const auto it = exif.findKey(Exiv2::ExifKey(key));
  if (it == exif.end() || it->count() == 0) return std::nullopt;
  const Exiv2::Rational r = it->toRational();
  const double value = r.second == 0 ? 0.0 : static_cast<double>(r.first) / r.second;
  if (!std::isfinite(value) || value <= 0.0) {
    ignored.push_back(it->tagName() + " = " + it->toString());
    return std::nullopt;
  }
  return value;
}

std::string text(const Exiv2::ExifData& exif, const char* key) {
  const auto it = exif.findKey(Exiv2::ExifKey(key));
  if (it == exif.end()) return {};
  std::string value = it->toString();
  while (!value.empty() && (value.back() == ' ' || value.back() == '\0')) value.pop_back();
  return value;
}

// "YYYY:MM:DD HH:MM:SS" (+ sub-second digits) -> s since 1970, read as UTC.
std::optional<double> exifTime(const std::string& when, const std::string& sub_seconds) {
  std::tm t{};
  if (std::sscanf(when.c_str(), "%d:%d:%d %d:%d:%d", &t.tm_year, &t.tm_mon, &t.tm_mday, &t.tm_hour,
                  &t.tm_min, &t.tm_sec) != 6 ||
      t.tm_year < 1900 || t.tm_mon < 1 || t.tm_mon > 12 || t.tm_mday < 1) {
    return std::nullopt;  // blank ("    :  :  ") or malformed
  }
  t.tm_year -= 1900;
  t.tm_mon -= 1;
  double seconds = static_cast<double>(timegm(&t));
  double scale = 0.1;
  for (char c : sub_seconds) {
    if (c < '0' || c > '9') break;
    seconds += scale * (c - '0');
    scale *= 0.1;
  }
  return seconds;
}

// FocalPlaneResolutionUnit: 2 inch, 3 cm, 4 mm, 5 um (the last two from DNG); 1 = none.
std::optional<double> millimetresPerUnit(long unit) {
  switch (unit) {
    case 2:
      return 25.4;
    case 3:
      return 10.0;
    case 4:
      return 1.0;
    case 5:
      return 1e-3;
    default:
      return std::nullopt;
  }
}

}  // namespace

ExifInfo readExif(const std::vector<unsigned char>& encoded) {
  static std::once_flag quiet;
  std::call_once(quiet, [] { Exiv2::LogMsg::setLevel(Exiv2::LogMsg::mute); });
  ExifInfo info;
  if (encoded.empty()) return info;
  try {
    auto image = Exiv2::ImageFactory::open(encoded.data(), static_cast<long>(encoded.size()));
    image->readMetadata();
    const Exiv2::ExifData& exif = image->exifData();
    if (exif.empty()) return info;
    const auto orientation = exif.findKey(Exiv2::ExifKey("Exif.Image.Orientation"));
    if (orientation != exif.end() && orientation->count() > 0) {
      const long value = orientation->toLong();
      if (value >= 1 && value <= 8) info.orientation = static_cast<int>(value);
    }
    info.focal_mm = positiveNumber(exif, "Exif.Photo.FocalLength", info.ignored);
    info.focal_35mm = positiveNumber(exif, "Exif.Photo.FocalLengthIn35mmFilm", info.ignored);
    const auto x_resolution =
        positiveNumber(exif, "Exif.Photo.FocalPlaneXResolution", info.ignored);
    const auto unit_key = exif.findKey(Exiv2::ExifKey("Exif.Photo.FocalPlaneResolutionUnit"));
    const long unit = unit_key != exif.end() && unit_key->count() > 0 ? unit_key->toLong() : 2;
    const auto mm = millimetresPerUnit(unit);  // the tag's default unit is the inch
    if (x_resolution && mm) info.focal_plane_x_per_mm = *x_resolution / *mm;
    const auto width = positiveNumber(exif, "Exif.Photo.PixelXDimension", info.ignored);
    const auto height = positiveNumber(exif, "Exif.Photo.PixelYDimension", info.ignored);
    if (width && height) {
      info.pixel_dimensions = cv::Size(static_cast<int>(*width), static_cast<int>(*height));
    }
    info.make = text(exif, "Exif.Image.Make");
    info.model = text(exif, "Exif.Image.Model");
    info.time_s = exifTime(text(exif, "Exif.Photo.DateTimeOriginal"),
                           text(exif, "Exif.Photo.SubSecTimeOriginal"));
  } catch (const std::exception&) {
    return ExifInfo{};  // unparsable metadata: the image itself decides
  }
  return info;
}

cv::Mat applyOrientation(const cv::Mat& stored, int orientation) {
  cv::Mat upright;
  switch (orientation) {
    case 2:
      cv::flip(stored, upright, 1);
      break;  // mirrored
    case 3:
      cv::rotate(stored, upright, cv::ROTATE_180);
      break;  // upside down
    case 4:
      cv::flip(stored, upright, 0);
      break;  // mirrored, flipped
    case 5:
      cv::transpose(stored, upright);
      break;  // transposed
    case 6:
      cv::rotate(stored, upright, cv::ROTATE_90_CLOCKWISE);
      break;  // held right
    case 7:
      cv::transpose(stored, upright);
      cv::flip(upright, upright, -1);
      break;  // transverse
    case 8:
      cv::rotate(stored, upright, cv::ROTATE_90_COUNTERCLOCKWISE);
      break;  // held left
    default:
      upright = stored;
  }
  return upright;
}

}  // namespace auv::recon::import
