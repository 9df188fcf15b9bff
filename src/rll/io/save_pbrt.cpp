// Writes a scene as a pbrt-v4 file: the camera (with pbrt's handedness fix), film, lights, sky,
// and one plymesh per material, each under the material and area light that reading it back
// maps onto the same rll material.
#include <fmt/format.h>

#include <algorithm>
#include <set>

#include "rll/core/error.h"
#include "rll/io/save.h"
#include "rll/scene/transform.h"

namespace rll {
namespace fs = std::filesystem;

namespace {

std::string rgb(const Rgb& c) {
  return fmt::format("[ {} {} {} ]", c.x, c.y, c.z);
}

bool grey(const Rgb& c) {
  return c.x == c.y && c.y == c.z;
}

// The equal-area square that a hemisphere sky (or any sky) looks like from inside: pbrt's
// infinite light covers the whole sphere, so the lower half is black for a hemisphere.
Image sky_image(const SkyDome& sky, int size) {
  Image img(size, size);
  const Frame frame(normalize(sky.up));
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const Vec3 d = equal_area_square_to_sphere(Vec2{(x + 0.5f) / size, (y + 0.5f) / size});
      if (!sky.full_sphere && dot(d, frame.n) <= 0) continue;
      img.at(x, y) = sky.radiance * (sky.map ? sky.map->lookup(d) : Rgb(1));
    }
  return img;
}

}  // namespace

std::vector<std::string> save_pbrt_scene(const Scene& scene, const fs::path& path) {
  if (path.extension() != ".pbrt") fail("{}: a pbrt scene is saved as a .pbrt file", path.string());
  const fs::path dir = path.parent_path();
  const std::string stem = path.stem().string();
  std::vector<std::string> warnings;
  auto warn = [&](std::string w) {
    if (std::find(warnings.begin(), warnings.end(), w) == warnings.end())
      warnings.push_back(std::move(w));
  };
  std::string out = fmt::format("# Written by rll from {}\n", scene.source);

  const Camera& c = scene.camera;
  if (scene.has_camera) {
    // pbrt's camera space is left-handed; mirroring x before LookAt makes its image the one rll
    // renders (and rll reads the file back without mirroring the world).
    out += "Scale -1 1 1\n";
    out += fmt::format("LookAt {} {} {}  {} {} {}  {} {} {}\n", c.position.x, c.position.y,
                       c.position.z, c.target.x, c.target.y, c.target.z, c.up.x, c.up.y, c.up.z);
    float fov = c.fov;  // pbrt's fov spans the shorter side
    if (scene.height > scene.width)
      fov = 2 * std::atan(std::tan(radians(c.fov) / 2) * scene.width / scene.height) * (180 / kPi);
    out += fmt::format("Camera \"perspective\" \"float fov\" [ {} ]\n", fov);
  }
  out += fmt::format("Film \"rgb\" \"integer xresolution\" [ {} ] \"integer yresolution\" [ {} ]\n",
                     scene.width, scene.height);
  out += "WorldBegin\n\n";

  for (const Light& l : scene.lights) {
    if (l.type == LightType::Point)
      out += fmt::format("LightSource \"point\" \"rgb I\" {} \"point3 from\" {}\n", rgb(l.radiance),
                         rgb(l.p0));
    else if (l.type == LightType::Directional)
      out += fmt::format(
          "LightSource \"distant\" \"rgb L\" {} \"point3 from\" {} \"point3 to\" [ 0 0 0 ]\n",
          rgb(l.radiance), rgb(l.p0));
  }
  if (scene.sky) {
    const SkyDome& sky = *scene.sky;
    if (sky.full_sphere && !sky.map) {
      out += fmt::format("LightSource \"infinite\" \"rgb L\" {}\n", rgb(sky.radiance));
    } else {
      // The sky (map, radiance and, for a hemisphere, the black half) baked into an equal-area
      // image in the world's frame.
      const std::string file = stem + "_sky.exr";
      write_image(dir / file, sky_image(sky, 256));
      out += fmt::format("LightSource \"infinite\" \"string filename\" \"{}\"\n", file);
      if (!sky.full_sphere)
        warn(
            "the hemisphere sky is written as a full-sphere environment map with a black lower "
            "half (pbrt has no dome); its horizon is resolved to the map's pixels");
    }
    if (sky.triangles != 2048)
      warn(
          fmt::format("the sky's {} triangles are not written (pbrt has no such setting); rll "
                      "reads an infinite light as 2048",
                      sky.triangles));
  }
  out += "\n";

  // Texture definitions go before the material that first uses them.
  std::set<std::string> textures;
  std::string pending;
  auto texture = [&](int index, float scale) {
    const std::string file = fmt::format("{}_tex{}.exr", stem, index);
    const std::string name =
        scale == 1 ? fmt::format("tex{}", index) : fmt::format("tex{}_x{}", index, scale);
    if (textures.insert(file).second) write_image(dir / file, scene.textures[size_t(index)]);
    if (textures.insert(name).second)
      pending += fmt::format(
          "Texture \"{}\" \"spectrum\" \"imagemap\" \"string filename\" \"{}\" "
          "\"string encoding\" \"linear\"{}\n",
          name, file, scale == 1 ? "" : fmt::format(" \"float scale\" {}", scale));
    return name;
  };
  // A material's reflectance: a colour, or a texture times a grey scale.
  auto reflectance = [&](const Material& m) {
    if (m.albedo_texture < 0) return fmt::format("\"rgb reflectance\" {}", rgb(m.albedo));
    if (!grey(m.albedo))
      warn(
          fmt::format("material '{}': a textured colour is written as the texture times a grey "
                      "scale (the colour's mean)",
                      m.name));
    const float scale = (m.albedo.x + m.albedo.y + m.albedo.z) / 3;
    return fmt::format("\"texture reflectance\" \"{}\"", texture(m.albedo_texture, scale));
  };

  int index = 0;
  for (const MaterialMesh& part : split_by_material(scene)) {
    const Material& m = scene.materials[part.material];
    std::string material;
    const std::string rough =
        fmt::format("\"float roughness\" {} \"bool remaproughness\" false", m.roughness);
    switch (m.type) {
      case MaterialType::Diffuse:
        material = fmt::format("Material \"diffuse\" {}", reflectance(m));
        break;
      case MaterialType::Plastic:
        material = fmt::format("Material \"coateddiffuse\" {} {} \"float eta\" {}", reflectance(m),
                               rough, m.ior);
        if (!(m.specular == Rgb(1)))
          warn(
              fmt::format("material '{}': pbrt's coateddiffuse has no specular tint; written "
                          "without it",
                          m.name));
        break;
      case MaterialType::Conductor:
        if (m.eta == kTintableEta && m.k == kTintableK) {
          material = fmt::format("Material \"conductor\" \"rgb reflectance\" {} {}",
                                 rgb(m.specular), rough);
        } else {
          material = fmt::format("Material \"conductor\" \"rgb eta\" {} \"rgb k\" {} {}",
                                 rgb(m.eta), rgb(m.k), rough);
          if (!(m.specular == Rgb(1)))
            warn(
                fmt::format("material '{}': pbrt's conductor has no tint besides eta and k; "
                            "written without it",
                            m.name));
        }
        break;
    }
    out += pending;
    pending.clear();
    const std::string file = fmt::format("{}_mesh{}.ply", stem, index++);
    write_file_atomic(dir / file, ply_bytes(part.mesh, PlyEncoding::BinaryLittleEndian));
    out += "AttributeBegin\n  " + material + "\n";
    if (m.is_emissive())
      out += fmt::format("  AreaLightSource \"diffuse\" \"rgb L\" {}{}\n", rgb(m.emission),
                         m.two_sided_emission ? " \"bool twosided\" true" : "");
    out += fmt::format("  Shape \"plymesh\" \"string filename\" \"{}\"\nAttributeEnd\n", file);
  }
  write_file_atomic(path, out);
  return warnings;
}

}  // namespace rll
