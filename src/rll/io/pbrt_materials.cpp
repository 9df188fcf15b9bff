// The pbrt reader's materials and textures (see pbrt_internal.h).
#include <array>
#include <cctype>
#include <functional>

#include "rll/io/pbrt_internal.h"
#include "rll/io/spectra.h"

namespace rll::pbrt {

// --- textures ---

// A texture parameter of a material or texture: a texture reference (`"texture NAME" "tex"`),
// or a value (float, rgb, spectrum...). nullopt when absent or when the reference is to a
// texture rll skipped (warned); a name no Texture directive defined before is an error, as in
// pbrt-v4.
std::optional<ImageTexture> PbrtReader::texture_operand(const Token& t, const Params& p,
                                                        const char* name, bool is_float) {
  if (auto tex = p.get_texture(name)) {
    auto it = m_textures.find(*tex);
    if (it == m_textures.end()) {
      if (!m_unread_textures.count(*tex))
        p.bad(*p.find(name), fmt::format("names texture \"{}\", which is not defined (a Texture "
                                         "directive must define it before its use)",
                                         printable(*tex)));
      warn("texture " + *tex, fmt::format("{}: texture \"{}\" is not a texture rll read; the "
                                          "parameter '{}' keeps its default",
                                          where(t), *tex, name));
      return std::nullopt;
    }
    return it->second;
  }
  ImageTexture c;
  if (is_float) {
    const Param* q = p.typed(name, {"float"});
    if (!q) return std::nullopt;
    c.scale = Rgb(float(p.one_number(*q)));
    return c;
  }
  auto v = p.get_spectrum(name);
  if (!v) return std::nullopt;
  c.scale = *v;
  return c;
}

// Combines textures texel by texel: constants give a constant, images (all of one size, with
// constants broadcast) a new image in Scene::textures. nullopt (warned) for images of different
// sizes.
std::optional<ImageTexture> PbrtReader::bake(const Token& t, const std::string& what,
                                             const std::vector<ImageTexture>& in,
                                             const std::function<Rgb(const Rgb*)>& f) {
  std::vector<Rgb> v(in.size());
  int w = -1, h = -1;
  for (size_t i = 0; i < in.size(); ++i) {
    v[i] = in[i].scale;
    if (in[i].index < 0) continue;
    const Image& img = m_scene.textures[size_t(in[i].index)];
    if (w >= 0 && (img.width() != w || img.height() != h)) {
      unsupported(t, fmt::format("{} of images of different sizes", what));
      return std::nullopt;
    }
    w = img.width();
    h = img.height();
  }
  ImageTexture out;
  if (w < 0) {
    out.scale = f(v.data());
    return out;
  }
  Image img(w, h);
  for (size_t px = 0; px < img.pixel_count(); ++px) {
    for (size_t i = 0; i < in.size(); ++i)
      if (in[i].index >= 0) v[i] = m_scene.textures[size_t(in[i].index)][px] * in[i].scale;
    img[px] = f(v.data());
  }
  m_scene.textures.push_back(std::move(img));
  out.index = int(m_scene.textures.size() - 1);
  return out;
}

void PbrtReader::texture(const Token& t) {
  const std::string name = expect_string(t), kind = expect_string(t), cls = expect_string(t);
  Params p(*this, t, fmt::format("Texture \"{}\"", name));
  // A texture rll skips (warned, and counted in the summary): references to it are warnings.
  auto skip = [&](const std::string& what) {
    m_unread_textures.insert(name);
    m_textures.erase(name);
    ++m_skipped_textures[what];
  };
  const bool is_float = kind == "float";
  if (!is_float && kind != "spectrum" && kind != "color" && kind != "rgb") {
    unsupported(t, fmt::format("Texture of type \"{}\"", kind));
    skip(kind);
    return;
  }
  std::optional<ImageTexture> result;
  if (cls == "imagemap") {
    result = image_texture(t, name, p);
  } else if (cls == "constant") {
    result = texture_operand(t, p, "value", is_float).value_or(ImageTexture{});
  } else if (cls == "scale") {
    // tex * scale: an image times a constant keeps the image; anything else is baked.
    auto tex = texture_operand(t, p, "tex", is_float).value_or(ImageTexture{});
    auto s = texture_operand(t, p, "scale", true).value_or(ImageTexture{});
    if (s.index < 0) {
      result = tex;
      result->scale = tex.scale * s.scale.x;
    } else if (tex.index < 0 && is_float) {
      result = s;
      result->scale = s.scale * tex.scale.x;
    } else {
      // A colour or an image scaled by a float image: baked texel by texel.
      result = bake(t, "Texture \"scale\"", {tex, s}, [](const Rgb* v) { return v[0] * v[1].x; });
    }
  } else if (cls == "mix") {
    // (1 - amount) tex1 + amount tex2.
    ImageTexture zero, one;
    zero.scale = Rgb(0);
    auto t1 = texture_operand(t, p, "tex1", is_float).value_or(zero);
    auto t2 = texture_operand(t, p, "tex2", is_float).value_or(one);
    ImageTexture half;
    half.scale = Rgb(0.5f);
    auto amount = texture_operand(t, p, "amount", true).value_or(half);
    result = bake(t, "Texture \"mix\"", {t1, t2, amount},
                  [](const Rgb* v) { return v[0] * (1 - v[2].x) + v[1] * v[2].x; });
  } else {
    unsupported(t, fmt::format("Texture class \"{}\"", cls));
    skip(cls);
    return;
  }
  if (!result) {
    skip(cls);
    return;
  }
  m_textures[name] = *result;
  m_unread_textures.erase(name);
  p.warn_unused();
}

std::optional<ImageTexture> PbrtReader::image_texture(const Token& t, const std::string& name,
                                                      const Params& p) {
  auto file = p.get_string("filename");
  if (!file) fail("{}: Texture \"{}\": imagemap needs a \"string filename\"", where(t), name);
  const fs::path path = referenced_file(t, "Texture", *file);
  std::string encoding = p.get_string("encoding").value_or("sRGB");
  if (encoding != "sRGB" && encoding != "linear") {
    warn("encoding " + encoding,
         fmt::format("{}: Texture: encoding \"{}\" is read as sRGB", where(t), encoding));
    encoding = "sRGB";
  }
  ImageTexture tex;
  tex.scale = Rgb(p.get_float("scale", 1));
  if (p.get_bool("invert", false)) unsupported(t, "Texture \"invert\"");
  for (const char* uv : {"uscale", "vscale"})
    if (p.get_float(uv, 1) != 1) unsupported(t, fmt::format("Texture \"{}\"", uv));
  for (const char* uv : {"udelta", "vdelta"})
    if (p.get_float(uv, 0) != 0) unsupported(t, fmt::format("Texture \"{}\"", uv));
  // The filter changes only how a texel is averaged (rll filters bilinearly); wrap modes and
  // mappings other than pbrt-v4's defaults change where the image lands.
  for (const char* ignored : {"filter", "maxanisotropy"}) p.find(ignored);
  for (const auto& [param, def, instead] :
       {std::tuple{"wrap", "repeat", "rll repeats the image"},
        std::tuple{"mapping", "uv", "rll maps the image by the shape's uv"}})
    if (const auto v = p.get_string(param); v && *v != def)
      warn(fmt::format("Texture {} {}", param, *v),
           fmt::format("{}: Texture \"{}\": \"string {}\" \"{}\" is not supported; {}",
                       where(t.file, p.find(param)->line), name, param, printable(*v), instead));
  auto cached = m_image_cache.find(path.string() + "|" + encoding);
  if (cached != m_image_cache.end()) {
    tex.index = cached->second;
  } else {
    try {
      m_scene.textures.push_back(read_image(path, encoding == "sRGB"));
    } catch (const Error& e) {
      fail("{}: Texture \"{}\": {}", where(t), name, e.what());
    }
    tex.index = int(m_scene.textures.size() - 1);
    m_image_cache[path.string() + "|" + encoding] = tex.index;
  }
  return tex;
}

// --- materials ---

// pbrt's roughness to rll's GGX alpha, as pbrt-v4's TrowbridgeReitzDistribution::RoughnessToAlpha:
// with "remaproughness" (the default) alpha = sqrt(roughness), else alpha = roughness. rll's GGX
// is isotropic: "uroughness" and "vroughness" (defaulting to "roughness") are mapped each and
// their alphas averaged. A textured roughness is baked into an image of alphas (its first
// channel), set as the material's roughness_texture.
void PbrtReader::roughness(const Token& t, const Params& p, Material& m, const std::string& prefix,
                           float def) {
  const bool remap = p.get_bool("remaproughness", true);
  // pbrt-v4 takes the square root of a roughness (or uses it as alpha): a negative one gives NaN
  // there, and would be clamped to a smooth surface here; either way not what the file meant.
  auto op = [&](const std::string& n) {
    const std::string name = prefix + n;
    auto v = texture_operand(t, p, name.c_str(), true);
    if (!v) return v;
    if (v->index < 0) {
      if (v->scale.x < 0)
        p.bad(*p.find(name.c_str()),
              fmt::format("is negative ({}): a roughness must be 0 or more", v->scale.x));
      return v;
    }
    const Image& img = m_scene.textures[size_t(v->index)];
    for (int y = 0; y < img.height(); ++y)
      for (int x = 0; x < img.width(); ++x)
        if (const float r = img.at(x, y).x * v->scale.x; r < 0 || !std::isfinite(r))
          p.bad(*p.find(name.c_str()),
                fmt::format("is {} at texel ({}, {}) of its texture: a roughness must be 0 or more",
                            r, x, y));
    return v;
  };
  ImageTexture d;
  d.scale = Rgb(def);
  const ImageTexture r = op("roughness").value_or(d);
  const ImageTexture u = op("uroughness").value_or(r), v = op("vroughness").value_or(r);
  auto alpha = [remap](float x) {
    x = std::max(0.0f, x);
    return remap ? std::sqrt(x) : x;
  };
  // Materials sharing a roughness texture share its image of alphas.
  const auto key = std::make_tuple(u.index, v.index, u.scale.x, v.scale.x, remap);
  std::optional<ImageTexture> baked;
  if (u.index >= 0 || v.index >= 0) {
    if (auto it = m_alpha_cache.find(key); it != m_alpha_cache.end()) baked = it->second;
  }
  if (!baked) {
    baked = bake(t, "roughness", {u, v},
                 [&](const Rgb* x) { return Rgb(0.5f * (alpha(x[0].x) + alpha(x[1].x))); });
    if (baked && baked->index >= 0) m_alpha_cache[key] = *baked;
  }
  if (!baked) return;
  if (baked->index < 0) {
    m.roughness = baked->scale.x;
  } else {
    m.roughness_texture = baked->index;
    m.roughness = 0.5f * (alpha(u.scale.x) + alpha(v.scale.x));  // unused while textured
  }
}

// The reflectance of a material: a colour, or an image texture (times its scale).
void PbrtReader::reflectance(const Token& t, const Params& p, const char* name, Material& m,
                             Rgb def) {
  m.albedo = def;
  auto tex = texture_operand(t, p, name, false);
  if (!tex) return;
  // pbrt-v4's diffuse and coated diffuse materials clamp their reflectance to [0, 1] where they
  // evaluate it (a surface cannot reflect more light than reaches it): rll clamps it here, a
  // texture texel by texel (before its bilinear filter, where pbrt-v4 clamps after it), and says
  // so once.
  auto in_range = [](const Rgb& c) { return min_component(c) >= 0 && max_component(c) <= 1; };
  const Param* q = p.find(name);
  auto say = [&](const std::string& what) {
    warn("reflectance outside [0, 1]",
         fmt::format("{}: parameter \"{} {}\" {}: clamped to [0, 1], as pbrt-v4 does (a "
                     "surface cannot reflect more light than reaches it)",
                     where(t.file, q->line), q->type, q->name, what));
  };
  if (tex->index < 0) {
    if (!in_range(tex->scale)) {
      say(fmt::format("is ({}, {}, {})", tex->scale.x, tex->scale.y, tex->scale.z));
      tex->scale = min(max(tex->scale, Rgb(0)), Rgb(1));
    }
  } else {
    const Image& img = m_scene.textures[size_t(tex->index)];
    const bool outside = std::any_of(img.pixels().begin(), img.pixels().end(),
                                     [&](const Rgb& c) { return !in_range(c * tex->scale); });
    if (outside) {
      const auto key = std::make_tuple(tex->index, tex->scale.x, tex->scale.y, tex->scale.z);
      auto it = m_clamped_cache.find(key);
      if (it == m_clamped_cache.end()) {
        auto baked = bake(t, "reflectance", {*tex},
                          [](const Rgb* v) { return min(max(v[0], Rgb(0)), Rgb(1)); });
        if (!baked) return;
        it = m_clamped_cache.emplace(key, *baked).first;
      }
      say("has texels outside [0, 1] (times its scale)");
      tex = it->second;
    }
  }
  m.albedo = tex->scale;
  m.albedo_texture = tex->index;
}

// A texture's mean value (a conductor's reflectance cannot vary over the surface in rll).
Rgb PbrtReader::mean_value(const ImageTexture& tex) const {
  if (tex.index < 0) return tex.scale;
  const Image& img = m_scene.textures[size_t(tex.index)];
  double s[3] = {0, 0, 0};
  for (const Rgb& c : img.pixels())
    for (int i = 0; i < 3; ++i) s[i] += c[i];
  const double n = std::max<double>(1, double(img.pixel_count()));
  return Rgb(float(s[0] / n), float(s[1] / n), float(s[2] / n)) * tex.scale;
}

// An index of refraction given as "float eta", a spectrum (named, such as "glass-BK7") or an
// rgb (its green value). pbrt-v4 checks none: it reads an eta of 0 as 1 and computes meaningless
// Fresnel terms for a negative one, so rll refuses both (an index of refraction is positive).
// An eta in (0, 1) is a relative index pbrt-v4 renders (the inside optically thinner than the
// outside): the caller decides what rll does with it.
float PbrtReader::ior_of(const Token& t, const std::string& material, const Params& p,
                         const char* name, float def) {
  const Param* e = p.find(name);
  if (!e) return def;
  float eta = def;
  if (e->type == "float")
    eta = float(p.one_number(*e));
  else if (auto c = p.get_spectrum(name))
    eta = c->y;
  if (!std::isfinite(eta) || !(eta > 0))
    syntax(t, fmt::format("Material \"{}\": \"{}\" must be a positive index of refraction (got "
                          "{})",
                          material, name, eta));
  return eta;
}

int PbrtReader::make_material(const Token& t, const std::string& type, const Params& p) {
  Material m;
  m.name = fmt::format("{} (line {})", type, t.line);
  for (const char* name : {"normalmap", "displacement"})
    if (const Param* q = p.find(name))
      warn(name, fmt::format("{}: Material \"{}\": parameter \"{} {}\" is not supported; "
                             "ignored (the surface is shaded with its mesh's own normals)",
                             where(t.file, q->line), type, q->type, name));
  if (type == "diffuse") {
    m.type = MaterialType::Diffuse;
    reflectance(t, p, "reflectance", m, Rgb(0.5f));
  } else if (type == "coateddiffuse") {
    // pbrt-v4's layered model: a dielectric coating (eta, roughness, thickness) over a
    // Lambertian base (reflectance).
    m.type = MaterialType::CoatedDiffuse;
    reflectance(t, p, "reflectance", m, Rgb(0.5f));
    roughness(t, p, m, "", 0);
    m.ior = ior_of(t, type, p, "eta", 1.5f);
    m.thickness = p.get_float("thickness", 0.01f);
    if (!(m.thickness > 0)) syntax(t, "Material \"coateddiffuse\": thickness must be positive");
    m.specular = Rgb(1);
    if (auto a = p.get_spectrum("albedo"); a && max_component(*a) > 0)
      unsupported(t, "Material \"coateddiffuse\" with a scattering layer (\"albedo\" > 0)");
    // "g" shapes the scattering layer, which an albedo of 0 leaves out (as in pbrt-v4).
    p.find("g");
    // rll's coated walk is pbrt-v4's with its defaults, fixed: say so where the file asks for
    // other values.
    for (const auto [name, def] : {std::pair{"maxdepth", 10}, std::pair{"nsamples", 1}})
      if (const Param* q = p.typed(name, {"integer"}); q && p.get_int(name, def) != def)
        warn(fmt::format("coateddiffuse {}", name),
             fmt::format("{}: Material \"coateddiffuse\": \"integer {}\" {} is ignored: rll's "
                         "coated walk always uses pbrt-v4's defaults, maxdepth 10 and nsamples 1",
                         where(t.file, q->line), name, p.get_int(name, def)));
  } else if (type == "conductor" || type == "coatedconductor") {
    m.type = MaterialType::Conductor;
    const std::string prefix = type == "conductor" ? "" : "conductor.";
    m.eta = *named_spectrum_rgb("metal-Cu-eta");  // pbrt's default metal is copper
    m.k = *named_spectrum_rgb("metal-Cu-k");
    if (auto e = p.get_spectrum((prefix + "eta").c_str())) m.eta = max(*e, Rgb(1e-3f));
    if (auto k = p.get_spectrum((prefix + "k").c_str())) m.k = *k;
    std::optional<Rgb> refl;
    if (p.get_texture("reflectance")) {
      if (auto tex = texture_operand(t, p, "reflectance", false)) {
        if (tex->index >= 0)
          unsupported(t, "a conductor's textured \"reflectance\" (its mean is used)");
        refl = mean_value(*tex);
      }
    } else {
      refl = p.get_spectrum("reflectance");
    }
    if (refl) {
      // pbrt-v4: eta = 1 and k = 2 sqrt(r) / sqrt(1 - r), r clamped to [0, 0.9999], which makes
      // the Fresnel reflectance at normal incidence, ((eta-1)^2 + k^2) / ((eta+1)^2 + k^2),
      // exactly r in each channel.
      m.eta = Rgb(1);
      for (int i = 0; i < 3; ++i) {
        const float r = clamp((*refl)[i], 0.0f, 0.9999f);
        m.k[i] = 2 * std::sqrt(r) / std::sqrt(1 - r);
      }
      m.specular = Rgb(1);
    }
    roughness(t, p, m, prefix, 0);
    if (type == "coatedconductor") {
      warn("coatedconductor", fmt::format("{}: Material \"coatedconductor\" is rendered as its "
                                          "conductor without the coating",
                                          where(t)));
      for (const char* name :
           {"interface.eta", "interface.roughness", "interface.uroughness", "interface.vroughness",
            "thickness", "albedo", "g", "maxdepth", "nsamples"})
        p.find(name);
    }
  } else if (type == "dielectric" || type == "thindielectric") {
    m.type = type == "dielectric" ? MaterialType::Dielectric : MaterialType::ThinDielectric;
    m.albedo = Rgb(0);
    m.specular = Rgb(1);
    m.ior = ior_of(t, type, p, "eta", 1.5f);
    if (m.ior < 1) {
      // rll's glass has its denser side inside (ior >= 1, as the JSON format requires).
      warn("eta below 1", fmt::format("{}: Material \"{}\" \"eta\" {} is below 1, which pbrt-v4 "
                                      "renders as an optically thinner inside; rll renders eta 1 "
                                      "(the surface is invisible)",
                                      where(t), type, m.ior));
      m.ior = 1;
    }
    if (type == "dielectric") {
      roughness(t, p, m, "", 0);
    } else {
      m.roughness = 0;  // pbrt's thin dielectric is smooth
    }
  } else if (type == "interface") {
    warn("interface", fmt::format("{}: Material \"interface\" (an invisible medium boundary) "
                                  "is not supported; its shapes are skipped",
                                  where(t)));
    return kInvisible;
  } else {
    warn("material " + type,
         fmt::format("{}: Material \"{}\" is not supported; rendered as diffuse grey 0.5", where(t),
                     type));
    m.albedo = Rgb(0.5f);
    p.find("reflectance");
    m_unsupported_materials.insert(type);
  }
  m_scene.materials.push_back(m);
  return int(m_scene.materials.size() - 1);
}

}  // namespace rll::pbrt
