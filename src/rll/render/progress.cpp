#include "rll/render/progress.h"

#include <fmt/format.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>

namespace rll {

std::string format_duration(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  if (s < 60) return fmt::format("{:.1f} s", s);
  int total = int(s + 0.5);
  if (total < 3600) return fmt::format("{} min {:02d} s", total / 60, total % 60);
  return fmt::format("{} h {:02d} min", total / 3600, (total / 60) % 60);
}

ProgressBar::ProgressBar(std::string label, bool enabled)
    : m_label(std::move(label)), m_enabled(enabled && ::isatty(STDERR_FILENO)) {}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::update(const RenderProgress& p) {
  if (!m_enabled) return;
  double frac = p.spp_target > 0 ? double(p.spp_done) / p.spp_target : 0;
  if (p.time_limit > 0) frac = std::max(frac, std::min(1.0, p.seconds / p.time_limit));
  const int width = 28;
  int filled = int(std::round(frac * width));
  std::string bar(size_t(filled), '#');
  bar.resize(width, '.');
  double rate = p.seconds > 0 ? p.samples / p.seconds : 0;
  double left = frac > 0 ? p.seconds * (1 - frac) / frac : NAN;
  std::string spp = p.spp_target >= kUnlimitedSpp ? fmt::format("{} spp", p.spp_done)
                                                   : fmt::format("{}/{} spp", p.spp_done, p.spp_target);
  fmt::print(stderr, "\r{} [{}] {}  {:.2f} M samples/s  {} elapsed, {} left   ", m_label, bar, spp,
             rate * 1e-6, format_duration(p.seconds), format_duration(left));
  std::fflush(stderr);
  m_drawn = true;
}

void ProgressBar::finish() {
  if (m_drawn) fmt::print(stderr, "\n");
  m_drawn = false;
}

}  // namespace rll
