// Scene loading speed: a generated 1,000,000-triangle binary PLY (a height-field grid with
// normals and uvs) read by load_ply, the same as ASCII, and the binary one loaded as a whole
// scene through a pbrt file (parse, then finalize: validation, lights, light tree). Goal: the
// binary PLY in under 2 s. Also: the binary PLY gzip-compressed (.ply.gz) through a pbrt
// plymesh, and a pbrt Shape "loopsubdiv" of a closed 2,000-triangle control mesh (a torus) at 3
// levels (128,000 triangles out), parsed and subdivided.
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
#include "rll/io/text_scan.h"

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

// A pbrt scene with one Shape "loopsubdiv": a closed torus of nu x nv quads (2 nu nv triangles,
// every vertex of valence 6) subdivided `levels` times.
std::string loopsubdiv_pbrt(int nu, int nv, int levels) {
  std::string s =
      "LookAt 0 4 -4  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
      "LightSource \"point\" \"point3 from\" [ 0 3 0 ]\n";
  s += fmt::format("Shape \"loopsubdiv\" \"integer levels\" {}\n  \"point3 P\" [", levels);
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double u = 2 * double(kPi) * i / nu, v = 2 * double(kPi) * j / nv;
      const double r = 1 + 0.35 * std::cos(v);
      s += fmt::format(" {:.6f} {:.6f} {:.6f}", r * std::cos(u), 0.35 * std::sin(v),
                       r * std::sin(u));
    }
  s += " ]\n  \"integer indices\" [";
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const int a = j * nu + i, b = j * nu + (i + 1) % nu, c = ((j + 1) % nv) * nu + i,
                d = ((j + 1) % nv) * nu + (i + 1) % nu;
      s += fmt::format(" {} {} {} {} {} {}", a, c, b, b, c, d);
    }
  return s + " ]\n";
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
  {
    const std::string gz = gzip(read_text_file(ply));
    std::ofstream(dir / "grid.ply.gz", std::ios::binary) << gz;
    fmt::print("{}: {:.1f} MB\n", (dir / "grid.ply.gz").string(), gz.size() / 1e6);
  }
  std::ofstream(dir / "grid_gz.pbrt") << "LookAt 0.5 2 -1  0.5 0 0.5  0 1 0\n"
                                         "Camera \"perspective\"\nWorldBegin\n"
                                         "LightSource \"point\" \"point3 from\" [ 0.5 1 0.5 ]\n"
                                         "Shape \"plymesh\" \"string filename\" \"grid.ply.gz\"\n";
  const int sub_nu = 40, sub_nv = 25, sub_levels = 3;  // 2,000 control triangles
  const size_t sub_triangles = size_t(2 * sub_nu * sub_nv) << (2 * sub_levels);
  std::ofstream(dir / "loop.pbrt") << loopsubdiv_pbrt(sub_nu, sub_nv, sub_levels);
  auto measure = [&](const char* what, size_t tris, auto&& load) {
    std::vector<double> t;
    for (int r = 0; r < repeats; ++r) {
      const auto t0 = Clock::now();
      load();
      t.push_back(seconds(t0));
    }
    std::sort(t.begin(), t.end());
    fmt::print("{:<52} min {:.3f} s  median {:.3f} s  ({} runs)  {:.2f} M triangles/s\n", what,
               t.front(), t[t.size() / 2], repeats, tris / t[t.size() / 2] / 1e6);
  };
  measure("load_ply (read + parse)", m.triangles.size(), [&] {
    Scene s;
    load_ply(ply, s);
    if (s.mesh.triangle_count() != m.triangles.size()) fail("wrong triangle count");
  });
  const fs::path ascii = dir / "grid_ascii.ply";
  std::ofstream(ascii, std::ios::binary) << ply_bytes(m, PlyEncoding::Ascii);
  measure("load_ply, the same mesh as ASCII", m.triangles.size(), [&] {
    Scene s;
    load_ply(ascii, s);
    if (s.mesh.triangle_count() != m.triangles.size()) fail("wrong triangle count");
  });
  LoadOptions quiet;
  quiet.print_warnings = false;
  measure("load_scene of a pbrt file with it (+finalize)", m.triangles.size(), [&] {
    Scene s = load_scene((dir / "grid.pbrt").string(), quiet);
    if (s.mesh.triangle_count() != m.triangles.size()) fail("wrong triangle count");
  });
  measure("load_scene of a pbrt file with it as .ply.gz", m.triangles.size(), [&] {
    Scene s = load_scene((dir / "grid_gz.pbrt").string(), quiet);
    if (s.mesh.triangle_count() != m.triangles.size()) fail("wrong triangle count");
  });
  const std::string loop_what = fmt::format("load_scene of a loopsubdiv ({} -> {} triangles)",
                                            2 * sub_nu * sub_nv, sub_triangles);
  measure(loop_what.c_str(), sub_triangles, [&] {
    Scene s = load_scene((dir / "loop.pbrt").string(), quiet);
    if (s.mesh.triangle_count() != sub_triangles) fail("wrong triangle count");
  });
  fs::remove_all(dir);
  return 0;
} catch (const std::exception& e) {
  fmt::print(stderr, "rll_bench_load: {}\n", e.what());
  return 1;
}
