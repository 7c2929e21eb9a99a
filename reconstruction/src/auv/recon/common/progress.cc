#include "auv/recon/common/progress.h"

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>

namespace auv::recon {

namespace {
using Clock = std::chrono::steady_clock;

Progress::Mode resolveMode(Progress::Mode mode, std::FILE* out) {
  if (const char* env = std::getenv("AUV_PROGRESS")) {
    if (std::strcmp(env, "bar") == 0) return Progress::Mode::BAR;
    if (std::strcmp(env, "plain") == 0) return Progress::Mode::PLAIN;
    if (std::strcmp(env, "quiet") == 0) return Progress::Mode::QUIET;
  }
  if (mode != Progress::Mode::AUTO) return mode;
  return ::isatty(::fileno(out)) ? Progress::Mode::BAR : Progress::Mode::PLAIN;
}

constexpr double kPlainPeriodS = 5.0;
constexpr double kBarPeriodS = 0.2;
constexpr int kBarWidth = 24;
}  // namespace

Progress::Progress(std::string what, std::string unit, size_t total, Mode mode, std::FILE* out)
    : what_(std::move(what)),
      unit_(std::move(unit)),
      total_(total),
      mode_(resolveMode(mode, out)),
      out_(out),
      start_(Clock::now()),
      last_draw_(Clock::now()) {}

Progress::~Progress() { finish(); }

std::string Progress::duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  const long s = std::lround(seconds);
  char text[32];
  if (s < 60) {
    std::snprintf(text, sizeof text, "%ld s", s);
  } else if (s < 3600) {
    std::snprintf(text, sizeof text, "%ld:%02ld", s / 60, s % 60);
  } else {
    std::snprintf(text, sizeof text, "%ld:%02ld:%02ld", s / 3600, (s / 60) % 60, s % 60);
  }
  return text;
}

void Progress::advance(size_t count) {
  std::lock_guard<std::mutex> lock(mutex_);
  done_ += count;
  drawLocked(false);
}

void Progress::setTotal(size_t total) {
  std::lock_guard<std::mutex> lock(mutex_);
  total_ = total;
}

size_t Progress::done() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return done_;
}

double Progress::seconds() const {
  return std::chrono::duration<double>(Clock::now() - start_).count();
}

void Progress::message(const std::string& text) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (mode_ == Mode::QUIET) return;
  if (bar_shown_) std::fprintf(out_, "\r\033[K");
  std::fprintf(out_, "%s\n", text.c_str());
  bar_shown_ = false;
  drawLocked(true);
}

void Progress::drawLocked(bool force) {
  if (mode_ == Mode::QUIET || finished_) return;
  const auto now = Clock::now();
  const double since = std::chrono::duration<double>(now - last_draw_).count();
  if (!force && since < (mode_ == Mode::BAR ? kBarPeriodS : kPlainPeriodS)) return;
  if (mode_ == Mode::PLAIN && force) return;  // plain lines only on their period
  last_draw_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double rate = elapsed > 0 ? done_ / elapsed : 0;
  const double eta = (rate > 0 && total_ > done_) ? (total_ - done_) / rate : 0;
  char numbers[160];
  if (total_ > 0) {
    std::snprintf(numbers, sizeof numbers, "%zu/%zu %s, %.1f/s, ETA %s", done_, total_,
                  unit_.c_str(), rate, duration(eta).c_str());
  } else {
    std::snprintf(numbers, sizeof numbers, "%zu %s, %.1f/s", done_, unit_.c_str(), rate);
  }
  if (mode_ == Mode::PLAIN) {
    std::fprintf(out_, "%s progress: %s\n", what_.c_str(), numbers);
  } else {
    std::string bar(kBarWidth, ' ');
    if (total_ > 0) {
      const size_t filled = std::min<size_t>(kBarWidth, done_ * kBarWidth / total_);
      bar.replace(0, filled, std::string(filled, '#'));
    }
    std::fprintf(out_, "\r\033[K%s [%s] %s", what_.c_str(), bar.c_str(), numbers);
    bar_shown_ = true;
  }
  std::fflush(out_);
}

void Progress::finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  finished_ = true;
  if (mode_ == Mode::QUIET) return;
  if (bar_shown_) std::fprintf(out_, "\r\033[K");
  const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
  std::fprintf(out_, "%s: %zu %s in %s (%.1f/s)\n", what_.c_str(), done_, unit_.c_str(),
               duration(elapsed).c_str(), elapsed > 0 ? done_ / elapsed : 0.0);
  std::fflush(out_);
}

}  // namespace auv::recon
