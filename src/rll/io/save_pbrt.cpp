// Writes a scene as a pbrt-v4 file: the camera (with pbrt's handedness fix), film, lights, sky,
// and one plymesh per material, each under the material and area light that reading it back
// maps onto the same rll material.
#include <fmt/format.h>

#include <algorithm>
#include <functional>
#include <set>

#include "rll/core/error.h"
#include "rll/core/file_checks.h"
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

// A goniometric or projection light: its image beside the file, under the transform whose
// inverse gives its rows back (see Light; a projection's fov from its first row, its frame taken
// as rigid).
std::string image_light(const Scene& scene, const Light& l, const fs::path& dir,
                        const std::string& file, const std::function<void(std::string)>& warn) {
  const Image& image = scene.textures.at(l.triangle);
  write_image(dir / file, image);
  Vec3 rows[3];
  std::string params;
  if (l.type == LightType::Goniometric) {
    rows[0] = l.p1;  // pbrt-v4 swaps y and z
    rows[1] = l.n;
    rows[2] = l.p2;
    params = fmt::format("LightSource \"goniometric\" \"rgb I\" {} \"string filename\" \"{}\"",
                         rgb(l.radiance), file);
  } else {
    const float aspect = float(image.width()) / float(image.height());
    const float xmax = aspect > 1 ? aspect : 1, ymax = aspect > 1 ? 1 : 1 / aspect;
    const float kx = 1 / length(l.p1), ky = 1 / length(l.p2);
    if (std::abs(kx / xmax - ky / ymax) > 1e-4f * (kx / xmax))
      warn("a projection light's image is stretched (a non-uniform transform): pbrt-v4's fov "
           "cannot say so; written with the horizontal one");
    rows[0] = l.p1 * kx;
    rows[1] = -l.p2 * ky;
    rows[2] = l.n;
    const float fov = 2 * std::atan(kx / xmax) * (180 / kPi);
    params = fmt::format("LightSource \"projection\" \"float scale\" [ {} ] \"float fov\" [ {} ] "
                         "\"string filename\" \"{}\"",
                         l.radiance.x, fov, file);
    if (!grey(l.radiance))
      warn("a projection light's colour scale is written as its red channel (pbrt-v4's has one "
           "scale)");
  }
  Affine to_light;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) to_light.a[i][j] = rows[i][j];
  Affine m = inverse(to_light);
  m.t = l.p0;
  return fmt::format(
      "AttributeBegin\n  Transform [ {} {} {} 0  {} {} {} 0  {} {} {} 0  {} {} {} 1 ]\n  {}\n"
      "AttributeEnd\n",
      m.a[0][0], m.a[1][0], m.a[2][0], m.a[0][1], m.a[1][1], m.a[2][1], m.a[0][2], m.a[1][2],
      m.a[2][2], m.t.x, m.t.y, m.t.z, params);
}

// Writes the files of save_pbrt_scene (inside its WriteBatch, which puts them in place together).
std::vector<std::string> write_pbrt_scene(const Scene& scene, const fs::path& path) {
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
    out += fmt::format("Camera \"perspective\" \"float fov\" [ {} ]", fov);
    // The thin lens and the screen window where they differ from pbrt-v4's defaults (which are
    // rll's).
    if (c.lens_radius != 0) out += fmt::format(" \"float lensradius\" [ {} ]", c.lens_radius);
    if (c.focal_distance != Camera().focal_distance)
      out += fmt::format(" \"float focaldistance\" [ {} ]", c.focal_distance);
    if (c.screen_window != Camera().screen_window) {
      // rll's screen units are tan(fov / 2) of the vertical side; pbrt's of the shorter one.
      const float k = scene.height > scene.width ? float(scene.width) / float(scene.height) : 1;
      const auto& w = c.screen_window;
      out += fmt::format(" \"float screenwindow\" [ {} {} {} {} ]", w[0] / k, w[1] / k, w[2] / k,
                         w[3] / k);
    }
    out += "\n";
  }
  out += fmt::format("Film \"rgb\" \"integer xresolution\" [ {} ] \"integer yresolution\" [ {} ]\n",
                     scene.width, scene.height);
  // rll's pixel filter: a box of one pixel (pbrt-v4's default is a Gaussian of radius 1.5).
  out += "PixelFilter \"box\" \"float xradius\" [ 0.5 ] \"float yradius\" [ 0.5 ]\n";
  out += "WorldBegin\n\n";

  for (const Light& l : scene.lights) {
    if (l.type == LightType::Point)
      out += fmt::format("LightSource \"point\" \"rgb I\" {} \"point3 from\" {}\n", rgb(l.radiance),
                         rgb(l.p0));
    else if (l.type == LightType::Directional)
      out += fmt::format(
          "LightSource \"distant\" \"rgb L\" {} \"point3 from\" {} \"point3 to\" [ 0 0 0 ]\n",
          rgb(l.radiance), rgb(l.p0));
    else if (l.has_image())
      out += image_light(scene, l, dir, fmt::format("{}_light{}.exr", stem, &l - scene.lights.data()),
                         warn);
    else if (l.type == LightType::Spot) {
      const SpotAngles a = spot_angles(l);
      out += fmt::format(
          "LightSource \"spot\" \"rgb I\" {} \"point3 from\" {} \"point3 to\" {} "
          "\"float coneangle\" [ {} ] \"float conedeltaangle\" [ {} ]\n",
          rgb(l.radiance), rgb(l.p0), rgb(l.p0 + l.n), a.cone, a.delta);
    }
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

  // A roughness texture: pbrt-v4's float image texture averages the channels, so the first
  // channel (the one rll reads) is written to all three.
  auto roughness_texture = [&](int index) {
    const std::string file = fmt::format("{}_rough{}.exr", stem, index);
    const std::string name = fmt::format("rough{}", index);
    if (textures.insert(file).second) {
      Image grey = scene.textures[size_t(index)];
      for (size_t i = 0; i < grey.pixel_count(); ++i) grey[i] = Rgb(grey[i].x);
      write_image(dir / file, grey);
      pending += fmt::format(
          "Texture \"{}\" \"float\" \"imagemap\" \"string filename\" \"{}\" "
          "\"string encoding\" \"linear\"\n",
          name, file);
    }
    return name;
  };
  // GGX alpha as it is: "remaproughness" false makes pbrt-v4 read roughness as alpha.
  auto roughness = [&](const Material& m) {
    if (m.roughness_texture >= 0)
      return fmt::format("\"texture roughness\" \"{}\" \"bool remaproughness\" false",
                         roughness_texture(m.roughness_texture));
    return fmt::format("\"float roughness\" {} \"bool remaproughness\" false", m.roughness);
  };

  int index = 0;
  for (const MaterialMesh& part : split_by_material(scene)) {
    const Material& m = scene.materials[part.material];
    std::string material;
    auto no_tint = [&](const char* pbrt_name) {
      if (!(m.specular == Rgb(1)))
        warn(fmt::format("material '{}': pbrt-v4's {} has no specular tint; written without it",
                         m.name, pbrt_name));
    };
    switch (m.type) {
      case MaterialType::Diffuse:
        material = fmt::format("Material \"diffuse\" {}", reflectance(m));
        break;
      case MaterialType::Plastic:
        material = fmt::format("Material \"coateddiffuse\" {} {} \"float eta\" {}",
                               reflectance(m), roughness(m), m.ior);
        warn(fmt::format(
            "material '{}': rll's plastic is written as pbrt-v4's coateddiffuse, which exchanges "
            "light between the coating and the base (rll's plastic does not): pbrt-v4 renders "
            "it darker and more saturated",
            m.name));
        no_tint("coateddiffuse");
        break;
      case MaterialType::CoatedDiffuse:
        material = fmt::format(
            "Material \"coateddiffuse\" {} {} \"float thickness\" {} \"float eta\" {}",
            reflectance(m), roughness(m), m.thickness, m.ior);
        break;
      case MaterialType::Dielectric:
        material = fmt::format("Material \"dielectric\" \"float eta\" {} {}", m.ior, roughness(m));
        break;
      case MaterialType::ThinDielectric:
        material = fmt::format("Material \"thindielectric\" \"float eta\" {}", m.ior);
        break;
      case MaterialType::Conductor:
        if (m.specular == Rgb(1)) {
          material = fmt::format("Material \"conductor\" \"rgb eta\" {} \"rgb k\" {} {}",
                                 rgb(m.eta), rgb(m.k), roughness(m));
        } else {
          // pbrt-v4's conductor has no tint; its "reflectance" r is a metal whose reflectance at
          // normal incidence is r (eta 1, k from r), which keeps the colour rll renders head-on.
          Rgb r;
          for (int i = 0; i < 3; ++i)
            r[i] = std::clamp(m.specular[i] * (sqr(m.eta[i] - 1) + sqr(m.k[i])) /
                                  (sqr(m.eta[i] + 1) + sqr(m.k[i])),
                              0.0f, 0.999f);
          material = fmt::format("Material \"conductor\" \"rgb reflectance\" {} {}", rgb(r),
                                 roughness(m));
          warn(fmt::format(
              "material '{}': pbrt-v4's conductor has no specular tint: the tinted metal is "
              "written as its reflectance at normal incidence (specular x the Fresnel "
              "reflectance of eta, k), which pbrt-v4 renders with a slightly different "
              "falloff towards grazing angles",
              m.name));
        }
        break;
    }
    out += pending;
    pending.clear();
    const std::string file = fmt::format("{}_mesh{}.ply", stem, index++);
    write_file_atomic(dir / file, ply_bytes(part.mesh, PlyEncoding::BinaryLittleEndian));
    out += "AttributeBegin\n  " + material + "\n";
    if (m.is_emissive() && m.emission_texture >= 0) {
      // pbrt-v4's image area light has a grey scale only: a coloured factor is baked into the
      // image written for this material.
      std::string image_file = fmt::format("{}_tex{}.exr", stem, m.emission_texture);
      float scale = m.emission.x;
      if (grey(m.emission)) {
        if (textures.insert(image_file).second)
          write_image(dir / image_file, scene.textures[size_t(m.emission_texture)]);
      } else {
        image_file = fmt::format("{}_emission{}.exr", stem, index);
        Image baked = scene.textures[size_t(m.emission_texture)];
        for (Rgb& c : baked.pixels()) c = c * m.emission;
        write_image(dir / image_file, baked);
        scale = 1;
      }
      out += fmt::format("  AreaLightSource \"diffuse\" \"string filename\" \"{}\" \"float scale\" {}{}\n",
                         image_file, scale, m.two_sided_emission ? " \"bool twosided\" true" : "");
    } else if (m.is_emissive()) {
      out += fmt::format("  AreaLightSource \"diffuse\" \"rgb L\" {}{}\n", rgb(m.emission),
                         m.two_sided_emission ? " \"bool twosided\" true" : "");
    }
    out += fmt::format("  Shape \"plymesh\" \"string filename\" \"{}\"\nAttributeEnd\n", file);
  }
  write_file_atomic(path, out);
  return warnings;
}

}  // namespace

std::vector<std::string> save_pbrt_scene(const Scene& scene, const fs::path& path) {
  if (path.extension() != ".pbrt") fail("{}: a pbrt scene is saved as a .pbrt file", path.string());
  // The .pbrt, its meshes and images replace an earlier conversion's together or not at all.
  WriteBatch batch;
  std::vector<std::string> warnings = write_pbrt_scene(scene, path);
  batch.commit();
  return warnings;
}

}  // namespace rll
