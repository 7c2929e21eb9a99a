#include "auv/recon/transfer/progress_display.h"

#include <cmath>

namespace auv::recon::transfer {

using Clock = std::chrono::steady_clock;

ProgressDisplay::ProgressDisplay(std::FILE* out, bool tty, double plain_period_s)
    : out_(out), tty_(tty), plain_period_s_(plain_period_s), last_plain_(Clock::now()) {}

std::string ProgressDisplay::bytes(double value) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  int unit = 0;
  while (value >= 1024.0 && unit < 4) value /= 1024.0, ++unit;
  char text[32];
  std::snprintf(text, sizeof(text), unit == 0 ? "%.0f %s" : "%.1f %s", value, units[unit]);
  return text;
}

std::string ProgressDisplay::duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  const long s = std::lround(seconds);
  char text[32];
  if (s < 60) {
    std::snprintf(text, sizeof(text), "%ld s", s);
  } else if (s < 3600) {
    std::snprintf(text, sizeof(text), "%ld:%02ld", s / 60, s % 60);
  } else {
    std::snprintf(text, sizeof(text), "%ld:%02ld:%02ld", s / 3600, (s / 60) % 60, s % 60);
  }
  return text;
}

std::string ProgressDisplay::line(const PullProgress& p, int bar_width) {
  // Rate over the last ~3 s: responsive, yet not jumping with every chunk.
  const auto now = Clock::now();
  samples_.emplace_back(now, p.bytes_done);
  while (samples_.size() > 2 && now - samples_.front().first > std::chrono::seconds(3)) {
    samples_.pop_front();
  }
  double rate = 0;
  const double span = std::chrono::duration<double>(now - samples_.front().first).count();
  if (span > 0.2) rate = (p.bytes_done - samples_.front().second) / span;
  const double fraction =
      p.bytes_total == 0 ? 1.0 : static_cast<double>(p.bytes_done) / p.bytes_total;
  std::string text;
  if (bar_width > 0) {
    const int filled = static_cast<int>(fraction * bar_width);
    text = "[" + std::string(filled, '#') + std::string(bar_width - filled, '.') + "] ";
  }
  char numbers[160];
  std::snprintf(numbers, sizeof(numbers), "%3.0f%% %s / %s  %s/s  ETA %s", 100.0 * fraction,
                bytes(p.bytes_done).c_str(), bytes(p.bytes_total).c_str(), bytes(rate).c_str(),
                rate > 0 ? duration((p.bytes_total - p.bytes_done) / rate).c_str() : "?");
  text += numbers;
  if (!p.waiting.empty()) {
    text += "  (" + p.waiting + ")";
  } else if (!p.current_file.empty()) {
    text += "  " + p.current_file;
  }
  return text;
}

void ProgressDisplay::update(const PullProgress& progress) {
  if (tty_) {
    std::string text = line(progress, 30);
    if (text.size() > 119) text.resize(119);
    std::fprintf(out_, "\r\033[K%s", text.c_str());
    std::fflush(out_);
    bar_shown_ = true;
    return;
  }
  const auto now = Clock::now();
  const std::string text = line(progress, 0);
  if (std::chrono::duration<double>(now - last_plain_).count() < plain_period_s_) return;
  last_plain_ = now;
  std::fprintf(out_, "pull progress: %s\n", text.c_str());
  std::fflush(out_);
}

void ProgressDisplay::message(const std::string& text) {
  finish();
  std::fprintf(out_, "%s\n", text.c_str());
  std::fflush(out_);
}

void ProgressDisplay::finish() {
  if (bar_shown_) std::fprintf(out_, "\r\033[K");
  bar_shown_ = false;
}

}  // namespace auv::recon::transfer
