#include "rll/scene/builtin.h"

#include <fmt/format.h>

#include <functional>
#include <memory>

#include "rll/core/error.h"
#include "rll/core/rng.h"
#include "rll/scene/builder.h"

namespace rll {

namespace {

Material make_conductor(const std::string& name, Rgb eta, Rgb k, float roughness) {
  Material m;
  m.name = name;
  m.type = MaterialType::Conductor;
  m.eta = eta;
  m.k = k;
  m.roughness = roughness;
  return m;
}

Material make_plastic(const std::string& name, Rgb albedo, float roughness) {
  Material m;
  m.name = name;
  m.type = MaterialType::Plastic;
  m.albedo = albedo;
  m.roughness = roughness;
  return m;
}

const Rgb kAluminiumEta{1.66f, 0.88f, 0.52f}, kAluminiumK{9.22f, 6.27f, 4.84f};
const Rgb kWhite{0.73f}, kRed{0.63f, 0.065f, 0.05f}, kGreen{0.14f, 0.45f, 0.091f};

// A Cornell box with its opening towards +z: lo/hi are its outer bounds. The lamp is a
// 2-triangle quad under the ceiling facing down, so it lights the inside of its own box.
void cornell_box(SceneBuilder& b, const Vec3& lo, const Vec3& hi, uint32_t white, uint32_t red,
                 uint32_t green, uint32_t lamp, float lamp_fraction) {
  // Walls face inwards; the +z side is open.
  b.box(lo, hi, white, true, (1u << 0) | (1u << 1) | (1u << 5));
  b.box(lo, hi, red, true, ~(1u << 0) & 63u);
  b.box(lo, hi, green, true, ~(1u << 1) & 63u);
  Vec3 d = hi - lo;
  float lw = d.x * lamp_fraction, ld = d.z * lamp_fraction;
  Vec3 p(lo.x + 0.5f * (d.x - lw), hi.y - 1e-3f * d.y, lo.z + 0.5f * (d.z - ld));
  b.quad(p, Vec3(lw, 0, 0), Vec3(0, 0, ld), lamp);  // x cross z = -y: faces down
}

Scene cornell_box_scene() {
  Scene s;
  s.width = s.height = 256;
  SceneBuilder b(s);
  uint32_t white = b.diffuse(kWhite, "white"), red = b.diffuse(kRed, "red"), green = b.diffuse(kGreen, "green");
  uint32_t lamp = b.emitter(Rgb(17, 12, 4), false, "lamp");
  uint32_t metal = b.material(make_conductor("aluminium", kAluminiumEta, kAluminiumK, 0.25f));
  cornell_box(b, Vec3(0, 0, 0), Vec3(1, 1, 1), white, red, green, lamp, 0.25f);
  b.box(Vec3(0.13f, 0, 0.37f), Vec3(0.43f, 0.3f, 0.67f), white);
  b.box(Vec3(0.55f, 0, 0.12f), Vec3(0.85f, 0.6f, 0.42f), metal);
  s.camera.position = Vec3(0.5f, 0.5f, 2.35f);
  s.camera.target = Vec3(0.5f, 0.5f, 0);
  s.camera.fov = 38;
  s.has_camera = true;
  return s;
}

// The room of the paper's Fig. 1. `lamps` (optional) receives, per Cornell box, the index of
// its lamp's first vertex (4 vertices) and its material, each lamp then getting its own.
struct LampInfo {
  uint32_t first_vertex, material;
};

Scene cornell_boxes_room_scene(std::vector<LampInfo>* lamps = nullptr) {
  Scene s;
  s.width = 400;
  s.height = 300;
  SceneBuilder b(s);
  const float W = 14, H = 6, D = 12;
  uint32_t wall = b.diffuse(Rgb(0.7f, 0.68f, 0.62f), "wall");
  uint32_t floor = b.diffuse(Rgb(0.45f, 0.42f, 0.4f), "floor");
  uint32_t white = b.diffuse(kWhite, "white"), red = b.diffuse(kRed, "red"), green = b.diffuse(kGreen, "green");
  uint32_t lamp = b.emitter(Rgb(12, 10, 7), false, "lamp");
  uint32_t plastic = b.material(make_plastic("blue-plastic", Rgb(0.1f, 0.2f, 0.5f), 0.15f));
  uint32_t metal = b.material(make_conductor("aluminium", kAluminiumEta, kAluminiumK, 0.2f));

  // The room: floor, back and front walls closed; ceiling skylights and side windows open.
  b.quad(Vec3(0, 0, 0), Vec3(0, 0, D), Vec3(W, 0, 0), floor);  // z cross x = +y
  b.quad(Vec3(0, 0, 0), Vec3(W, 0, 0), Vec3(0, H, 0), wall);   // back wall, faces +z
  b.quad(Vec3(0, 0, D), Vec3(0, H, 0), Vec3(W, 0, 0), wall);   // front wall, faces -z
  std::vector<SceneBuilder::Hole> skylights;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 2; ++j) {
      float z0 = 3.0f + j * 4.0f, x0 = 2.5f + i * 3.75f;
      skylights.push_back({z0, x0, z0 + 1.4f, x0 + 1.5f});  // (u = z, v = x) in the y plane
    }
  b.wall_with_holes(1, H, 0, 0, D, W, skylights, false, wall);
  std::vector<SceneBuilder::Hole> windows;  // (u = y, v = z) in the x planes
  for (int k = 0; k < 3; ++k) windows.push_back({2.6f, 2.5f + k * 3.0f, 4.6f, 3.7f + k * 3.0f});
  b.wall_with_holes(0, 0, 0, 0, H, D, windows, true, wall);
  b.wall_with_holes(0, W, 0, 0, H, D, windows, false, wall);

  // 42 Cornell boxes stacked 7 x 6 against the back wall, opening towards the camera.
  const int cols = 7, rows = 6;
  const float bw = 1.4f, bh = 0.78f, bd = 1.0f, pitch_x = 1.8f, pitch_y = 0.9f;
  const float x_margin = 0.5f * (W - cols * pitch_x) + 0.5f * (pitch_x - bw);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      Vec3 lo(x_margin + c * pitch_x, 0.15f + r * pitch_y, 0.05f);
      uint32_t own_lamp = lamp;
      if (lamps) {
        own_lamp = b.emitter(Rgb(12, 10, 7), false, fmt::format("lamp-{}-{}", r, c));
        // The lamp quad is the last thing cornell_box adds: its 4 vertices end the array.
        cornell_box(b, lo, lo + Vec3(bw, bh, bd), white, red, green, own_lamp, 0.3f);
        lamps->push_back({uint32_t(s.mesh.positions.size() - 4), own_lamp});
        continue;
      }
      cornell_box(b, lo, lo + Vec3(bw, bh, bd), white, red, green, own_lamp, 0.3f);
    }
  b.sphere(Vec3(4.5f, 0.9f, 6.5f), 0.9f, 3, plastic);
  b.box(Vec3(8.8f, 0, 5.5f), Vec3(10.3f, 1.2f, 7.0f), metal);

  SkyDome sky;
  sky.triangles = 2048;
  sky.radiance = Rgb(0.55f, 0.7f, 1.0f) * 1.6f;
  s.sky = sky;
  s.camera.position = Vec3(W * 0.5f, 3.0f, D - 0.5f);
  s.camera.target = Vec3(W * 0.5f, 2.7f, 0);
  s.camera.fov = 52;
  s.has_camera = true;
  return s;
}

// cornell-boxes-room animated: between frames, about a fifth of the lamps switch off or back
// on and the lamps of every other column slide sideways inside their boxes. Every lamp is on
// when the scene is built, so that each of its triangles is a light at every frame.
Scene cornell_boxes_dynamic_scene() {
  auto lamps = std::make_shared<std::vector<LampInfo>>();
  Scene s = cornell_boxes_room_scene(lamps.get());
  auto base = std::make_shared<std::vector<Vec3>>();
  for (const auto& l : *lamps)
    for (uint32_t v = 0; v < 4; ++v) base->push_back(s.mesh.positions[l.first_vertex + v]);
  const Rgb on(12, 10, 7);
  s.frame_count = 8;
  s.animate = [lamps, base, on](Scene& scene, int frame) {
    for (size_t i = 0; i < lamps->size(); ++i) {
      const LampInfo& l = (*lamps)[i];
      bool lit = (i * 7 + size_t(frame) * 3) % 5 != 0 || frame == 0;
      scene.materials[l.material].emission = lit ? on : Rgb(0);
      // Columns alternate: even ones slide by up to 0.45 (the box is 1.4 wide, the lamp 0.42).
      float shift = (i % 2 == 0) ? 0.45f * std::sin(0.9f * float(frame) + float(i)) : 0.0f;
      if (frame == 0) shift = 0;
      for (uint32_t v = 0; v < 4; ++v)
        scene.mesh.positions[l.first_vertex + v] = (*base)[4 * i + v] + Vec3(shift, 0, 0);
    }
  };
  return s;
}

Scene arch_interior_scene() {
  Scene s;
  s.width = 400;
  s.height = 300;
  SceneBuilder b(s);
  const float W = 16, H = 4, D = 10;
  uint32_t wall = b.diffuse(Rgb(0.75f, 0.72f, 0.68f), "plaster");
  uint32_t floor = b.diffuse(Rgb(0.35f, 0.25f, 0.18f), "wood");
  uint32_t stone = b.diffuse(Rgb(0.55f, 0.55f, 0.52f), "stone");
  uint32_t plastic = b.material(make_plastic("red-plastic", Rgb(0.5f, 0.08f, 0.06f), 0.2f));
  uint32_t metal = b.material(make_conductor("aluminium", kAluminiumEta, kAluminiumK, 0.3f));

  b.quad(Vec3(0, 0, 0), Vec3(0, 0, D), Vec3(W, 0, 0), floor);  // floor, faces +y
  b.quad(Vec3(0, H, 0), Vec3(W, 0, 0), Vec3(0, 0, D), wall);   // ceiling, faces -y
  b.quad(Vec3(W, 0, 0), Vec3(0, 0, D), Vec3(0, H, 0), wall);   // right wall (x=W), faces -x
  b.quad(Vec3(0, 0, D), Vec3(0, H, 0), Vec3(W, 0, 0), wall);   // front wall, faces -z
  // Many small windows: a 12 x 2 grid in the left wall (x = 0), a 10 x 2 grid in the back wall.
  std::vector<SceneBuilder::Hole> left, back;
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 2; ++j) {
      float z0 = 0.45f + i * 0.8f, y0 = 1.5f + j * 1.2f;
      left.push_back({y0, z0, y0 + 0.7f, z0 + 0.35f});  // (u = y, v = z)
    }
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 2; ++j) {
      float x0 = 0.9f + i * 1.5f, y0 = 1.5f + j * 1.2f;
      back.push_back({x0, y0, x0 + 0.45f, y0 + 0.7f});  // (u = x, v = y)
    }
  b.wall_with_holes(0, 0, 0, 0, H, D, left, true, wall);
  b.wall_with_holes(2, 0, 0, 0, W, H, back, true, wall);
  // Columns and furniture.
  for (int i = 0; i < 4; ++i) b.box(Vec3(2.5f + i * 3.5f, 0, 3.0f), Vec3(2.9f + i * 3.5f, H, 3.4f), stone);
  b.box(Vec3(5.0f, 0, 5.5f), Vec3(8.0f, 0.8f, 7.0f), stone);
  b.sphere(Vec3(10.5f, 0.7f, 6.0f), 0.7f, 3, plastic);
  b.box(Vec3(12.0f, 0, 4.5f), Vec3(13.0f, 1.6f, 5.5f), metal);

  SkyDome sky;
  sky.triangles = 2048;
  sky.radiance = Rgb(0.5f, 0.65f, 1.0f) * 1.5f;
  s.sky = sky;
  s.lights.push_back(make_directional_light(Vec3(-1.0f, 0.9f, -0.45f), Rgb(9, 8, 6.5f)));
  s.camera.position = Vec3(W - 1.0f, 2.0f, D - 0.6f);
  s.camera.target = Vec3(5.0f, 1.4f, 1.0f);
  s.camera.fov = 60;
  s.has_camera = true;
  return s;
}

// Small emissive triangles on a jittered nx x nz grid over [x0,x1] x [z0,z1] at heights
// [y0, y0 + dy], each facing down within 30 degrees, with colours and radiances drawn from
// `palette` materials.
void emitter_field(SceneBuilder& b, Pcg32& rng, int nx, int nz, float x0, float x1, float z0, float z1,
                   float y0, float dy, float size, const std::vector<uint32_t>& palette) {
  Mesh& mesh = b.scene().mesh;
  mesh.positions.reserve(mesh.positions.size() + size_t(nx) * nz * 3);
  mesh.triangles.reserve(mesh.triangles.size() + size_t(nx) * nz);
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < nz; ++j) {
      Vec3 c(x0 + (x1 - x0) * (i + rng.next_float()) / nx, y0 + dy * rng.next_float(),
             z0 + (z1 - z0) * (j + rng.next_float()) / nz);
      Vec3 nrm = normalize(Vec3(rng.next_float() - 0.5f, -1.0f, rng.next_float() - 0.5f));
      Frame f(nrm);
      float r = size * (1 + rng.next_float());
      Vec3 a = c + f.s * r, bb = c + (f.s * -0.5f + f.t * 0.866f) * r, cc = c + (f.s * -0.5f - f.t * 0.866f) * r;
      if (dot(cross(bb - a, cc - a), nrm) < 0) std::swap(bb, cc);  // front face along nrm
      b.triangle(a, bb, cc, palette[rng.next_bounded(uint32_t(palette.size()))]);
    }
}

std::vector<uint32_t> emitter_palette(SceneBuilder& b, Pcg32& rng, int count) {
  std::vector<uint32_t> mats;
  for (int k = 0; k < count; ++k) {
    Rgb c(0.3f + 0.7f * rng.next_float(), 0.3f + 0.7f * rng.next_float(), 0.3f + 0.7f * rng.next_float());
    mats.push_back(b.emitter(c * (4.0f + 36.0f * rng.next_float() * rng.next_float()), false));
  }
  return mats;
}

Scene many_lights_open_scene() {
  Scene s;
  s.width = 400;
  s.height = 300;
  SceneBuilder b(s);
  uint32_t floor = b.diffuse(Rgb(0.6f), "floor");
  b.quad(Vec3(-25, 0, -25), Vec3(0, 0, 50), Vec3(50, 0, 0), floor);
  // 128 x 80 = 10,240 small emitters of varied colour and radiance; nothing but the emitters
  // themselves stands between them and the floor.
  Pcg32 rng(7);
  auto palette = emitter_palette(b, rng, 16);
  emitter_field(b, rng, 128, 80, -16, 16, -10, 10, 0.4f, 3.0f, 0.06f, palette);
  s.camera.position = Vec3(0, 9, 20);
  s.camera.target = Vec3(0, 0, 0);
  s.camera.fov = 55;
  s.has_camera = true;
  return s;
}

Scene many_lights_1m_scene() {
  Scene s;
  s.width = 200;
  s.height = 150;
  SceneBuilder b(s);
  uint32_t floor = b.diffuse(Rgb(0.6f), "floor");
  uint32_t grey = b.diffuse(Rgb(0.5f), "grey");
  b.quad(Vec3(-120, 0, -120), Vec3(0, 0, 240), Vec3(240, 0, 0), floor);
  // 1000 x 1000 tiny emitters over 200 x 200 units, and a few blocks casting shadows.
  Pcg32 rng(11);
  auto palette = emitter_palette(b, rng, 32);
  emitter_field(b, rng, 1000, 1000, -100, 100, -100, 100, 1.0f, 4.0f, 0.02f, palette);
  for (int k = 0; k < 12; ++k) {
    Vec3 lo(-60 + 10.0f * k, 0, -10.0f + 4.0f * float(k % 3));
    b.box(lo, lo + Vec3(3, 0.8f, 3), grey);
  }
  s.camera.position = Vec3(0, 25, 70);
  s.camera.target = Vec3(0, 0, 0);
  s.camera.fov = 50;
  s.has_camera = true;
  return s;
}

// A hall of rooms_x x rooms_z roofless rooms (4 x 4 units, walls 3 high with a doorway in the
// middle of each), each with a shelf and a grid of spots x spots spot lights hung at 2.8 that
// point down with a random tilt and a narrow cone (12-30 degrees): each spot lights a patch of
// its own room, and a little of the next through the doorways. `mixed` adds a point light, a
// lamp (2 emissive triangles) and a dim sun, so that every kind of light meets in one tree.
Scene spot_hall_scene(int rooms_x, int rooms_z, int spots, bool mixed) {
  Scene s;
  s.width = 400;
  s.height = 300;
  SceneBuilder b(s);
  constexpr float kRoom = 4, kHeight = 3, kWall = 0.1f, kDoor = 1.0f, kDoorHeight = 2.2f;
  uint32_t floor = b.diffuse(Rgb(0.6f), "floor"), wall = b.diffuse(Rgb(0.7f, 0.68f, 0.62f), "wall");
  uint32_t shelf = b.diffuse(Rgb(0.45f, 0.3f, 0.2f), "shelf");
  const float sx = rooms_x * kRoom, sz = rooms_z * kRoom;
  b.quad(Vec3(0, 0, 0), Vec3(0, 0, sz), Vec3(sx, 0, 0), floor);
  // Walls along x = const and z = const, each room's stretch split by a doorway (a lintel above).
  auto wall_run = [&](bool along_z, float at, float from, float to) {
    auto slab = [&](float a, float c, float y0, float y1) {
      if (along_z)
        b.box(Vec3(at - kWall / 2, y0, a), Vec3(at + kWall / 2, y1, c), wall);
      else
        b.box(Vec3(a, y0, at - kWall / 2), Vec3(c, y1, at + kWall / 2), wall);
    };
    const float mid = 0.5f * (from + to);
    slab(from, mid - kDoor / 2, 0, kHeight);
    slab(mid + kDoor / 2, to, 0, kHeight);
    slab(mid - kDoor / 2, mid + kDoor / 2, kDoorHeight, kHeight);
  };
  for (int i = 0; i <= rooms_x; ++i)
    for (int k = 0; k < rooms_z; ++k) wall_run(true, i * kRoom, k * kRoom, (k + 1) * kRoom);
  for (int k = 0; k <= rooms_z; ++k)
    for (int i = 0; i < rooms_x; ++i) wall_run(false, k * kRoom, i * kRoom, (i + 1) * kRoom);
  Pcg32 rng(23);
  const Rgb tints[4] = {Rgb(1.0f, 0.85f, 0.6f), Rgb(0.8f, 0.9f, 1.0f), Rgb(1.0f, 0.7f, 0.7f),
                        Rgb(0.9f, 1.0f, 0.8f)};
  for (int i = 0; i < rooms_x; ++i)
    for (int k = 0; k < rooms_z; ++k) {
      const Vec3 o(i * kRoom, 0, k * kRoom);
      // A shelf against a random wall of the room.
      const float along = 0.6f + 1.4f * rng.next_float();
      if (rng.next_float() < 0.5f)
        b.box(o + Vec3(0.3f, 0, along), o + Vec3(0.7f, 1.8f, along + 1.6f), shelf);
      else
        b.box(o + Vec3(along, 0, 0.3f), o + Vec3(along + 1.6f, 1.8f, 0.7f), shelf);
      for (int a = 0; a < spots; ++a)
        for (int c = 0; c < spots; ++c) {
          const Vec3 pos = o + Vec3(kRoom * (a + 0.5f) / spots, 2.8f, kRoom * (c + 0.5f) / spots);
          const Vec3 dir(1.2f * (rng.next_float() - 0.5f), -1, 1.2f * (rng.next_float() - 0.5f));
          const float cone = 12 + 18 * rng.next_float(), delta = 2 + 6 * rng.next_float();
          const Rgb I = tints[rng.next_bounded(4)] * (0.4f + 0.8f * rng.next_float()) *
                        (100.0f / float(spots * spots));
          s.lights.push_back(make_spot_light(pos, dir, I, std::cos(radians(cone - delta)),
                                             std::cos(radians(cone))));
        }
    }
  if (mixed) {
    s.lights.push_back(make_point_light(Vec3(kRoom * 0.5f, 1.5f, kRoom * 0.5f), Rgb(2.0f)));
    s.lights.push_back(make_directional_light(Vec3(0.3f, 1, 0.2f), Rgb(0.2f)));
    const uint32_t lamp = b.emitter(Rgb(6, 5, 4), false, "lamp");
    b.quad(Vec3(sx - kRoom * 0.6f, 2.9f, kRoom * 0.4f), Vec3(0.4f, 0, 0), Vec3(0, 0, 0.4f), lamp);
    // pbrt-v4's image lights: a goniometric light whose equal-area profile (around its y axis,
    // the map's +z) is brightest downwards, and a projector casting a 4 x 4 pattern on a floor.
    Image profile(8, 8), slide(4, 4);
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x)
        profile.at(x, y) = Rgb(0.2f + 0.8f * float((x + y) % 5) / 4);
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 4; ++x)
        slide.at(x, y) = (x + y) % 2 ? Rgb(1.0f, 0.3f, 0.2f) : Rgb(0.2f, 0.4f, 1.0f);
    const Vec3 gonio_rows[3] = {Vec3(1, 0, 0), Vec3(0, 0, 1), Vec3(0, -1, 0)};
    Light gonio = make_image_light(LightType::Goniometric, Vec3(kRoom * 0.5f, 2.5f, sz - kRoom * 0.5f),
                                   gonio_rows, Rgb(1.5f), uint32_t(s.textures.size()), 0);
    gonio.area = image_light_power_factor(gonio, profile);
    s.textures.push_back(std::move(profile));
    s.lights.push_back(gonio);
    // Projecting straight down (its z = world -y) with a 50 degree fov.
    const float k = 1 / std::tan(radians(25));
    const Vec3 slide_rows[3] = {Vec3(k, 0, 0), Vec3(0, 0, k), Vec3(0, -1, 0)};
    Light projector = make_image_light(LightType::Projection, Vec3(sx - kRoom * 0.5f, 2.7f, sz - kRoom * 0.5f),
                                       slide_rows, Rgb(4.0f), uint32_t(s.textures.size()), 0);
    projector.area = image_light_power_factor(projector, slide);
    s.textures.push_back(std::move(slide));
    s.lights.push_back(projector);
  }
  s.camera.position = Vec3(0.5f * sx, 0.9f * std::max(sx, sz) + 6, sz + 0.35f * std::max(sx, sz) + 2);
  s.camera.target = Vec3(0.5f * sx, 0, 0.5f * sz);
  s.camera.fov = 50;
  s.has_camera = true;
  return s;
}

// A room lit only by a sky dome, through glazed windows: thin panes (pbrt-v4's thindielectric)
// in the left and back walls and two smooth glass slabs in the back wall, and one open skylight
// in the ceiling. Through the Dirac glass no light sample gets through (a shadow ray stops at the
// pane) and the sky is found by the BSDF ray alone; through the skylight every light sampler
// takes part, as it does for the ground outside. There is no sun: a path tracer cannot carry a
// delta light through Dirac glass.
Scene glazed_room_scene() {
  Scene s;
  s.width = 400;
  s.height = 300;
  SceneBuilder b(s);
  const float W = 8, H = 3, D = 6;
  uint32_t wall = b.diffuse(Rgb(0.75f, 0.73f, 0.7f), "plaster");
  uint32_t floor = b.diffuse(Rgb(0.45f, 0.36f, 0.28f), "oak");
  uint32_t grey = b.diffuse(Rgb(0.5f, 0.5f, 0.48f), "grey");
  Material pane;
  pane.name = "pane";
  pane.type = MaterialType::ThinDielectric;
  pane.ior = 1.5f;
  Material glass = pane;
  glass.name = "glass";
  glass.type = MaterialType::Dielectric;
  glass.roughness = 0;
  Material coated;
  coated.name = "coated-green";
  coated.type = MaterialType::CoatedDiffuse;
  coated.albedo = Rgb(0.15f, 0.45f, 0.25f);
  coated.roughness = 0.1f;
  Material coated_red = coated;
  coated_red.name = "coated-red";
  coated_red.albedo = Rgb(0.6f, 0.12f, 0.08f);
  coated_red.roughness = 0;
  uint32_t m_pane = b.material(pane), m_glass = b.material(glass);
  uint32_t m_coated = b.material(coated), m_coated_red = b.material(coated_red);

  b.quad(Vec3(0, 0, 0), Vec3(0, 0, D), Vec3(W, 0, 0), floor);  // floor, faces +y
  b.quad(Vec3(W, 0, 0), Vec3(0, 0, D), Vec3(0, H, 0), wall);   // right wall (x=W), faces -x
  b.quad(Vec3(0, 0, D), Vec3(0, H, 0), Vec3(W, 0, 0), wall);   // front wall, faces -z
  // Ground outside, just below the floor.
  b.quad(Vec3(-100, -0.01f, -100), Vec3(0, 0, 200), Vec3(200, 0, 0), b.diffuse(Rgb(0.3f, 0.32f, 0.25f), "ground"));
  // Ceiling (y = H, faces -y) with one open skylight: (u = z, v = x).
  b.wall_with_holes(1, H, 0, 0, D, W, {{2.2f, 4.6f, 3.0f, 5.4f}}, false, wall);
  // Left wall (x = 0): three tall windows, each glazed with a thin pane; (u = y, v = z).
  std::vector<SceneBuilder::Hole> left;
  for (int i = 0; i < 3; ++i) left.push_back({0.3f, 0.6f + i * 1.7f, 2.6f, 1.9f + i * 1.7f});
  b.wall_with_holes(0, 0, 0, 0, H, D, left, true, wall);
  for (const auto& h : left)  // the pane's front faces the room (+x)
    b.quad(Vec3(0, h.u0, h.v0), Vec3(0, h.u1 - h.u0, 0), Vec3(0, 0, h.v1 - h.v0), m_pane);
  // Back wall (z = 0): four windows, (u = x, v = y); the outer two thin panes, the inner two
  // 4 cm slabs of glass.
  std::vector<SceneBuilder::Hole> back;
  for (int i = 0; i < 4; ++i) back.push_back({0.6f + i * 1.8f, 0.4f, 1.9f + i * 1.8f, 2.6f});
  b.wall_with_holes(2, 0, 0, 0, W, H, back, true, wall);
  for (int i = 0; i < 4; ++i) {
    const auto& h = back[size_t(i)];
    if (i == 1 || i == 2)
      b.box(Vec3(h.u0, h.v0, -0.02f), Vec3(h.u1, h.v1, 0.02f), m_glass);
    else  // faces the room (+z)
      b.quad(Vec3(h.u0, h.v0, 0), Vec3(h.u1 - h.u0, 0, 0), Vec3(0, h.v1 - h.v0, 0), m_pane);
  }
  // Furniture: a table, a coated cabinet, a coated ball and a plain one.
  b.box(Vec3(2.0f, 0.7f, 2.2f), Vec3(3.8f, 0.78f, 3.4f), grey);
  for (float x : {2.05f, 3.65f})
    for (float z : {2.25f, 3.25f}) b.box(Vec3(x, 0, z), Vec3(x + 0.1f, 0.7f, z + 0.1f), grey);
  b.box(Vec3(7.1f, 0, 2.4f), Vec3(7.9f, 1.3f, 3.9f), m_coated);
  b.sphere(Vec3(2.9f, 1.08f, 2.8f), 0.3f, 3, m_coated_red);
  b.sphere(Vec3(5.2f, 0.45f, 3.6f), 0.45f, 3, grey);

  SkyDome sky;
  sky.triangles = 1024;
  sky.radiance = Rgb(0.5f, 0.65f, 1.0f) * 4.0f;
  sky.radius_scale = 4;  // the ground already reaches far
  s.sky = sky;
  s.camera.position = Vec3(W - 0.5f, 2.1f, D - 0.3f);
  s.camera.target = Vec3(2.5f, 0.6f, 1.0f);
  s.camera.fov = 65;
  s.has_camera = true;
  return s;
}

// A quad whose uvs span [0, 1]^2 (u along e1, v along e2), whatever the mesh held before.
void textured_quad(SceneBuilder& b, const Vec3& p, const Vec3& e1, const Vec3& e2, uint32_t material) {
  Mesh& mesh = b.scene().mesh;
  b.quad(p, e1, e2, material);
  mesh.uvs.resize(mesh.positions.size(), Vec2{});
  static const Vec2 kCorners[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (size_t k = 0; k < 4; ++k) mesh.uvs[mesh.positions.size() - 4 + k] = kCorners[k];
}

// The screens' pictures, made here (no image files): colour bars over a ramp with a bright disc,
// a stained-glass window of coloured panes between dark leads, and a dim checkerboard with a
// bright diagonal band. Linear radiance factors, row 0 at the top.
Image colour_bars_picture() {
  const int w = 64, h = 36;
  const Rgb bars[8] = {{1, 1, 1},       {1, 1, 0.1f},   {0.1f, 1, 1}, {0.1f, 1, 0.1f},
                       {1, 0.1f, 1},    {1, 0.1f, 0.1f}, {0.1f, 0.1f, 1}, {0.05f, 0.05f, 0.05f}};
  Image img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      Rgb c = y < 24 ? bars[x * 8 / w] : Rgb(float(x) / float(w - 1)) * 0.8f;
      const float dx = float(x) - 44.5f, dy = float(y) - 12.5f;
      if (dx * dx + dy * dy < 30) c = Rgb(4.0f, 3.6f, 3.0f);
      img.at(x, y) = c;
    }
  return img;
}

Image stained_glass_picture() {
  const int w = 48, h = 96;
  const Rgb glass[6] = {{0.9f, 0.15f, 0.1f}, {0.15f, 0.3f, 1.0f}, {1.0f, 0.8f, 0.1f},
                        {0.1f, 0.8f, 0.3f},  {0.7f, 0.2f, 0.9f},  {1.0f, 1.0f, 0.9f}};
  Image img(w, h);
  Pcg32 rng(7);
  std::vector<Rgb> panes(6 * 12);
  for (Rgb& p : panes) p = glass[rng.next_u32() % 6] * (0.6f + 0.8f * rng.next_float());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool lead = x % 8 == 0 || y % 8 == 0;
      img.at(x, y) = lead ? Rgb(0.0f) : panes[size_t(y / 8) * 6 + size_t(x / 8)];
    }
  return img;
}

Image checker_band_picture() {
  const int w = 40, h = 40;
  Image img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      Rgb c = ((x / 5 + y / 5) % 2) ? Rgb(0.15f, 0.2f, 0.3f) : Rgb(0.02f);
      if (std::abs(x - y) < 3) c = Rgb(3.0f, 2.2f, 1.2f);
      img.at(x, y) = c;
    }
  return img;
}

// A hall lit by three large textured emitters (a screen, a stained-glass window, a light panel)
// and 12 small lamps, with partitions and pillars in between so that visibility matters.
Scene screen_hall_scene() {
  Scene s;
  s.width = 400;
  s.height = 300;
  SceneBuilder b(s);
  const float W = 12, H = 4, D = 10;
  uint32_t wall = b.diffuse(Rgb(0.7f, 0.7f, 0.68f), "plaster");
  uint32_t floor = b.diffuse(Rgb(0.4f, 0.33f, 0.27f), "oak");
  uint32_t grey = b.diffuse(Rgb(0.45f), "grey");
  b.box(Vec3(0, 0, 0), Vec3(W, H, D), wall, true, 1u << 5);  // open towards the camera (+z)
  b.quad(Vec3(0, 0.001f, 0), Vec3(0, 0, D), Vec3(W, 0, 0), floor);
  auto picture = [&](Image img, const Rgb& factor, const std::string& name) {
    s.textures.push_back(std::move(img));
    Material m;
    m.name = name;
    m.albedo = Rgb(0.05f);
    m.emission = factor;
    m.emission_texture = int(s.textures.size() - 1);
    return b.material(m);
  };
  // The screen on the back wall (faces +z), the window on the left wall (faces +x), the panel on
  // the right wall (faces -x).
  textured_quad(b, Vec3(3.0f, 0.8f, 0.01f), Vec3(6.0f, 0, 0), Vec3(0, 3.0f, 0),
                picture(colour_bars_picture(), Rgb(2.5f), "screen"));
  textured_quad(b, Vec3(0.01f, 0.6f, 6.5f), Vec3(0, 0, -3.0f), Vec3(0, 3.0f, 0),
                picture(stained_glass_picture(), Rgb(3.0f), "stained-glass"));
  textured_quad(b, Vec3(W - 0.01f, 1.0f, 2.0f), Vec3(0, 0, 2.5f), Vec3(0, 2.5f, 0),
                picture(checker_band_picture(), Rgb(2.0f), "panel"));
  // Partitions and pillars between the emitters and the room.
  b.box(Vec3(2.0f, 0, 3.0f), Vec3(5.5f, 2.4f, 3.15f), grey);
  b.box(Vec3(7.0f, 0, 4.0f), Vec3(10.5f, 2.0f, 4.15f), grey);
  b.box(Vec3(1.2f, 0, 2.0f), Vec3(1.5f, H, 2.3f), grey);
  for (float x : {4.0f, 8.0f}) b.box(Vec3(x, 0, 6.5f), Vec3(x + 0.35f, H, 6.85f), grey);
  b.box(Vec3(5.5f, 0, 7.0f), Vec3(6.5f, 0.9f, 8.0f), grey);
  // Small lamps under the ceiling (facing down), some behind the partitions.
  uint32_t lamp = b.emitter(Rgb(40.0f, 32.0f, 22.0f), false, "lamp");
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) {
      const float x = 1.2f + 3.0f * float(i), z = 1.5f + 3.0f * float(k);
      b.quad(Vec3(x, H - 0.01f, z), Vec3(0.2f, 0, 0), Vec3(0, 0, 0.2f), lamp);
    }
  s.camera.position = Vec3(W * 0.5f, 2.0f, D + 3.5f);
  s.camera.target = Vec3(W * 0.45f, 1.6f, 0);
  s.camera.fov = 60;
  s.has_camera = true;
  return s;
}

Scene furnace_scene() {
  Scene s;
  s.width = s.height = 32;
  SceneBuilder b(s);
  Material m;
  m.name = "furnace";
  m.albedo = Rgb(kFurnaceAlbedo);
  m.emission = Rgb(kFurnaceEmission);
  // Flat facets: smooth shading normals would make the answer only approximately analytic
  // (0.2% per bounce); the closed polyhedron gives exactly Le * sum a^k.
  b.sphere(Vec3(0), 1.0f, 2, b.material(m), true, false);
  s.camera.position = Vec3(0, 0, 0);
  s.camera.target = Vec3(0, 0, 1);
  s.camera.fov = 60;
  s.has_camera = true;
  return s;
}

struct Entry {
  BuiltinSceneInfo info;
  std::function<Scene()> make;
};

const std::vector<Entry>& entries() {
  static const std::vector<Entry> e = {
      {{"cornell-box", "the classic Cornell box with one area light (2 triangles) and a metal block"},
       cornell_box_scene},
      {{"cornell-boxes-room",
        "the paper's Fig. 1/3: 42 Cornell boxes, each lit by its own 2-triangle lamp, in a room lit "
        "by a 2048-triangle sky dome through skylights and windows"},
       [] { return cornell_boxes_room_scene(); }},
      {{"cornell-boxes-dynamic",
        "cornell-boxes-room animated over 8 frames (--frames): lamps switch on and off and slide inside "
        "their boxes; learning carries over between frames"},
       cornell_boxes_dynamic_scene},
      {{"arch-interior",
        "the paper's Fig. 4: a room lit only by a 2048-triangle sky dome and a sun through 44 small windows"},
       arch_interior_scene},
      {{"many-lights-open", "10,240 small emissive triangles over an open floor, nothing occluded"},
       many_lights_open_scene},
      {{"many-lights-1m", "stress test: 1,000,000 tiny emissive triangles over a floor with a few blocks"},
       many_lights_1m_scene},
      {{"glazed-room",
        "a room lit only by a 1024-triangle sky dome through 7 glazed windows (thin panes and glass "
        "slabs) and an open skylight, with coated-diffuse furniture"},
       glazed_room_scene},
      {{"spot-hall",
        "102,400 spot lights (pbrt-v4's smoothstep cones) over a hall of 16 x 16 roofless rooms with "
        "doorways and shelves: each spot lights a patch of its own room"},
       [] { return spot_hall_scene(16, 16, 20, false); }},
      {{"spot-hall-small",
        "spot-hall's 2 x 2 rooms with 36 spots each, a point light, a 2-triangle lamp, a dim sun, a "
        "goniometric light and a projector (every light kind in one tree; for tests)"},
       [] { return spot_hall_scene(2, 2, 6, true); }},
      {{"screen-hall",
        "a hall lit by three large textured emitters (a screen, a stained-glass window, a light "
        "panel; pictures made in code) and 12 small lamps, behind partitions and pillars"},
       screen_hall_scene},
      {{"furnace", "inside an emissive diffuse sphere (Le = 1, albedo 0.5): radiance sum of 0.5^k"},
       furnace_scene},
  };
  return e;
}

}  // namespace

const std::vector<BuiltinSceneInfo>& builtin_scenes() {
  static const std::vector<BuiltinSceneInfo> infos = [] {
    std::vector<BuiltinSceneInfo> v;
    for (const auto& e : entries()) v.push_back(e.info);
    return v;
  }();
  return infos;
}

Scene make_builtin_scene(const std::string& name) {
  for (const auto& e : entries())
    if (e.info.name == name) {
      Scene s = e.make();
      s.source = "builtin:" + name;
      return s;
    }
  std::string list;
  for (const auto& e : entries()) list += (list.empty() ? "" : ", ") + e.info.name;
  fail("unknown built-in scene '{}' (available: {})", name, list);
}

}  // namespace rll
