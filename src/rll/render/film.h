// HDR accumulation of pixel samples (sum and count per pixel).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "rll/core/device.h"
#include "rll/core/image.h"

namespace rll {

// What one sample's camera vertex (the first surface its path hit) saw of the light sampler, for
// the per-pixel diagnostics (render/aov.h).
struct CameraVertexSample {
  static constexpr uint32_t kNone = ~0u;
  uint32_t cell = kNone;  // the sampler's cell of the point (rll, fermat, oracle)
  float light_pmf = 0;    // the pmf of the light its next-event sample chose
  bool sampled = false;   // a next-event sample was taken there
  uint32_t shadow = 0;    // light samples there that count a shadow ray ...
  uint32_t visible = 0;   // ... and those whose shadow ray reached the light
};

// Per pixel, the sums of its samples' camera vertices: the last sample's cell, the chosen
// lights' pmfs and how many, the shadow rays and those that reached their light.
struct CameraVertexSums {
  std::vector<uint32_t> cell;
  std::vector<double> light_pmf;
  std::vector<uint32_t> sampled, shadow, visible;
};

// A film's sums and counts as a kernel adds to them (in host or device memory).
struct FilmView {
  View<double> sum;  // 3 per pixel
  View<uint32_t> count;
  int width = 0;

  // Not thread-safe per pixel: one thread adds a pixel's samples, in their order.
  RLL_HD void add(size_t pixel, const Rgb& v) const {
    add_sum(pixel, v);
    ++count[pixel];
  }
  // Adds to the sums of a sample already counted (a filtered path's share, render/psf.h).
  RLL_HD void add_sum(size_t pixel, const Rgb& v) const {
    sum[3 * pixel] += v.x;
    sum[3 * pixel + 1] += v.y;
    sum[3 * pixel + 2] += v.z;
  }
};

// The bytes a render holds for each pixel of its film: the sums (3 doubles) and the sample count,
// the image resolved from them, and what writing it adds (an .exr share's counts, a .png's 8-bit
// pixels and their encoding).
inline constexpr double kRenderBytesPerPixel = 3 * 8 + 4 + 3 * 4 + 8;
// What --aov adds: the camera-vertex sums (Film::track_camera_vertex); each channel written adds 4.
inline constexpr double kCameraVertexBytesPerPixel = 4 + 8 + 3 * 4;

// What kRenderBytesPerPixel holds, for messages.
inline constexpr const char* kRenderPixelText =
    "its sums, sample counts and the image written from them";

// Refuses, before anything is allocated, a film of width x height whose pixels at
// `bytes_per_pixel` (what `kept` says they hold) need more than the memory budget
// (core/memory_budget.h), with a message naming the resolution, `source` (what set it:
// "--res 16384x16384", "the film of scene 'x.pbrt'") and what to do. A 300-byte pbrt file can
// ask for a 16384x16384 film: 11 GB.
void check_film_memory(int64_t width, int64_t height, double bytes_per_pixel,
                       const std::string& source, const std::string& kept = kRenderPixelText);

class Film {
 public:
  Film(int width, int height)
      : m_w(width),
        m_h(height),
        m_sum(size_t(width) * height * 3, 0.0),
        m_count(size_t(width) * height, 0) {}
  int width() const { return m_w; }
  int height() const { return m_h; }
  // Not thread-safe per pixel: each pixel is owned by one tile at a time.
  void add(int x, int y, const Rgb& v) { view().add(size_t(y) * m_w + x, v); }
  // Keeps per-pixel sums of the camera vertices too (render() then asks the integrator for them).
  void track_camera_vertex();
  // Null unless tracked.
  const CameraVertexSums* camera_vertex() const {
    return m_vertex.cell.empty() ? nullptr : &m_vertex;
  }
  // Not thread-safe per pixel, as add().
  void add_camera_vertex(int x, int y, const CameraVertexSample& v);
  FilmView view() { return {view_of(m_sum), view_of(m_count), m_w}; }
  uint32_t count(int x, int y) const { return m_count[size_t(y) * m_w + x]; }
  uint32_t min_count() const;
  const std::vector<uint32_t>& counts() const { return m_count; }
  // Mean of the samples per pixel (black where no sample landed yet).
  Image resolve() const;
  void clear();

 private:
  int m_w, m_h;
  std::vector<double> m_sum;  // double: references accumulate many thousand samples
  std::vector<uint32_t> m_count;
  CameraVertexSums m_vertex;
};

}  // namespace rll
