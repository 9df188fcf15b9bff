// Scene loading speed: a generated 1,000,000-triangle binary PLY (a height-field grid with
// normals and uvs) read by load_ply, the same as ASCII, and the binary one loaded as a whole
// scene through a pbrt file (parse, then finalize: validation, lights, light tree). Goal: the
// binary PLY in under 2 s.
// Usage: rll_bench_load [TRIANGLES] [REPEATS]
#include <fmt/format.h>

#include <unistd.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <vector>

#include "rll/core/error.h"
#include "rll/io/load.h"
#include "rll/io/save.h"

using namespace rll;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

namespace {

double seconds(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// A grid of nx x ny quads (2 triangles each) over a gentle height field.
Mesh grid(int nx, int ny) {
  Mesh m;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const float x = float(i) / nx, y = float(j) / ny;
      const float h = 0.05f * std::sin(12 * x) * std::cos(9 * y);
      m.positions.push_back(Vec3(x, h, y));
      m.normals.push_back(normalize(Vec3(-0.6f * std::cos(12 * x) * std::cos(9 * y), 1,
                                         0.45f * std::sin(12 * x) * std::sin(9 * y))));
      m.uvs.push_back(Vec2{x, y});
    }
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const uint32_t a = uint32_t(j * (nx + 1) + i), b = a + 1, c = a + uint32_t(nx + 1), d = c + 1;
      m.triangles.push_back({a, c, b});
      m.triangles.push_back({b, c, d});
    }
  return m;
}

}  // namespace

int main(int argc, char** argv) try {
  const long triangles = argc > 1 ? std::atol(argv[1]) : 1000000;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 5;
  const int nx = 1000, ny = int(std::max(1L, triangles / (2 * nx)));
  const fs::path dir = fs::temp_directory_path() / fmt::format("rll-bench-load-{}", ::getpid());
  fs::create_directories(dir);
  const Mesh m = grid(nx, ny);
  const fs::path ply = dir / "grid.ply";
  {
    const std::string bytes = ply_bytes(m, PlyEncoding::BinaryLittleEndian);
    std::ofstream(ply, std::ios::binary) << bytes;
    fmt::print("{}: {} triangles, {} vertices, {:.1f} MB\n", ply.string(), m.triangles.size(),
               m.positions.size(), bytes.size() / 1e6);
  }
  std::ofstream(dir / "grid.pbrt") << "LookAt 0.5 2 -1  0.5 0 0.5  0 1 0\n"
                                      "Camera \"perspective\"\nWorldBegin\n"
                                      "LightSource \"point\" \"point3 from\" [ 0.5 1 0.5 ]\n"
                                      "Shape \"plymesh\" \"string filename\" \"grid.ply\"\n";
  auto measure = [&](const char* what, auto&& load) {
    std::vector<double> t;
    for (int r = 0; r < repeats; ++r) {
      const auto t0 = Clock::now();
      load();
      t.push_back(seconds(t0));
    }
    std::sort(t.begin(), t.end());
    fmt::print("{:<44} min {:.3f} s  median {:.3f} s  ({} runs)\n", what, t.front(),
               t[t.size() / 2], repeats);
  };
  measure("load_ply (read + parse)", [&] {
    Scene s;
    load_ply(ply, s);
    if (s.mesh.triangle_count() != m.triangles.size()) fail("wrong triangle count");
  });
  const fs::path ascii = dir / "grid_ascii.ply";
  std::ofstream(ascii, std::ios::binary) << ply_bytes(m, PlyEncoding::Ascii);
  measure("load_ply, the same mesh as ASCII", [&] {
    Scene s;
    load_ply(ascii, s);
    if (s.mesh.triangle_count() != m.triangles.size()) fail("wrong triangle count");
  });
  LoadOptions quiet;
  quiet.print_warnings = false;
  measure("load_scene of a pbrt file with it (+finalize)", [&] {
    Scene s = load_scene((dir / "grid.pbrt").string(), quiet);
    if (s.mesh.triangle_count() != m.triangles.size()) fail("wrong triangle count");
  });
  fs::remove_all(dir);
  return 0;
} catch (const std::exception& e) {
  fmt::print(stderr, "rll_bench_load: {}\n", e.what());
  return 1;
}
