// Writes the fuzz targets' seed corpora: small valid files of each format, made by rll's own
// writers (PLY, gzip, glTF, OBJ + MTL, EXR) or written out here (pbrt and JSON, which must not
// refer to other files), and images in the formats stb_image reads (by stb_image_write). Usage:
// rll_fuzz_seeds DIR  (writes DIR/ply, DIR/gltf, DIR/pbrt, DIR/json, DIR/obj, DIR/gzip, DIR/exr,
// DIR/image)
#include <fmt/format.h>
#include <stb/stb_image_write.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "../fuzz/fuzz_input.h"
#include "rll/core/error.h"
#include "rll/core/image.h"
#include "rll/io/load.h"
#include "rll/io/save.h"
#include "rll/io/text_scan.h"
#include "rll/scene/builder.h"

namespace fs = std::filesystem;
using namespace rll;

namespace {

void write(const fs::path& p, const std::string& bytes) {
  std::ofstream f(p, std::ios::binary);
  f << bytes;
  if (!f) fail("cannot write {}", p.string());
}

Scene small_scene() {
  Scene s;
  s.source = "seed";
  SceneBuilder b(s);
  Material plastic;
  plastic.type = MaterialType::Plastic;
  Material metal;
  metal.type = MaterialType::Conductor;
  b.box(Vec3(0), Vec3(1), b.diffuse(Rgb(0.7f)), true, 1u << 5);
  b.sphere(Vec3(0.5f, 0.3f, 0.5f), 0.2f, 0, b.material(plastic));
  b.quad(Vec3(0.1f, 0.01f, 0.1f), Vec3(0.2f, 0, 0), Vec3(0, 0, 0.2f), b.material(metal));
  b.quad(Vec3(0.4f, 0.99f, 0.4f), Vec3(0, 0, 0.2f), Vec3(0.2f, 0, 0), b.emitter(Rgb(5, 4, 3)));
  s.lights.push_back(make_point_light(Vec3(0.5f), Rgb(1)));
  s.lights.push_back(make_directional_light(normalize(Vec3(1, 2, 3)), Rgb(2)));
  s.has_camera = true;
  s.camera.position = Vec3(0.5f, 0.5f, 3);
  s.camera.target = Vec3(0.5f);
  return s;
}

// A GLB holding a .gltf's JSON (whose buffer is a data URI) and no binary chunk.
std::string glb_of(std::string json) {
  while (json.size() % 4) json += ' ';
  std::string out = "glTF";
  auto u32 = [&](uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
  u32(2);
  u32(uint32_t(20 + json.size()));
  u32(uint32_t(json.size()));
  u32(0x4E4F534A);
  return out + json;
}

// An image of w x h pixels with `channels` channels as stb_image_write encodes it in `format`
// (png, jpg, bmp, tga, hdr).
std::string encoded_image(const std::string& format, int w, int h, int channels) {
  std::vector<unsigned char> px(size_t(w) * size_t(h) * size_t(channels));
  std::vector<float> fpx(px.size());
  for (size_t i = 0; i < px.size(); ++i) {
    px[i] = static_cast<unsigned char>((i * 37) % 256);
    fpx[i] = float(i % 7) * 0.75f;
  }
  std::string out;
  auto append = [](void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), size_t(size));
  };
  int ok = 0;
  if (format == "png") ok = stbi_write_png_to_func(append, &out, w, h, channels, px.data(), 0);
  if (format == "jpg") ok = stbi_write_jpg_to_func(append, &out, w, h, channels, px.data(), 80);
  if (format == "bmp") ok = stbi_write_bmp_to_func(append, &out, w, h, channels, px.data());
  if (format == "tga") ok = stbi_write_tga_to_func(append, &out, w, h, channels, px.data());
  if (format == "hdr") ok = stbi_write_hdr_to_func(append, &out, w, h, channels, fpx.data());
  if (!ok) fail("cannot encode a {} seed", format);
  return out;
}

const char* kPbrtSeeds[] = {
    R"(LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" [ 45 ]
Film "rgb" "integer xresolution" [ 32 ] "integer yresolution" [ 24 ]
Sampler "halton" "integer pixelsamples" 4
WorldBegin
LightSource "point" "rgb I" [ 1 1 1 ] "point3 from" [ 0 2 0 ]
LightSource "distant" "point3 from" [ 0 1 0 ] "point3 to" [ 0 0 0 ] "blackbody L" 5500
AttributeBegin
  Material "diffuse" "rgb reflectance" [ 0.5 0.4 0.3 ]
  AreaLightSource "diffuse" "rgb L" [ 4 4 4 ] "bool twosided" true
  Translate 0 1 0
  Shape "trianglemesh" "point3 P" [ 0 0 0 1 0 0 0 1 0 ] "integer indices" [ 0 1 2 ]
    "normal N" [ 0 0 1 0 0 1 0 0 1 ] "point2 uv" [ 0 0 1 0 0 1 ]
AttributeEnd
)",
    R"(Scale -1 1 1
LookAt 1 2 3 0 0 0 0 0 1
Camera "perspective"
WorldBegin
MakeNamedMaterial "gold" "string type" "conductor" "spectrum eta" "metal-Au-eta"
  "spectrum k" "metal-Au-k" "float roughness" 0.1
MakeNamedMaterial "glass" "string type" "dielectric" "float eta" 1.5
ObjectBegin "ball"
  NamedMaterial "gold"
  Shape "sphere" "float radius" 0.5 "float zmin" -0.2 "float phimax" 270
ObjectEnd
AttributeBegin Translate 1 0 0 Rotate 30 0 1 0 ObjectInstance "ball" AttributeEnd
AttributeBegin Scale 2 2 2 ObjectInstance "ball" AttributeEnd
NamedMaterial "glass"
Shape "disk" "float radius" 2 "float innerradius" 0.5
Material "coateddiffuse" "rgb reflectance" [ 0.2 0.2 0.8 ] "float roughness" 0.05
Shape "bilinearmesh" "point3 P" [ 0 0 0 1 0 0 0 1 0 1 1 1 ] "integer indices" [ 0 1 2 3 ]
LightSource "infinite" "rgb L" [ 0.3 0.4 0.5 ]
)",
    R"(Transform [ 1 0 0 0  0 1 0 0  0 0 1 0  0 0 -5 1 ]
Camera "perspective" "float fov" 30
WorldBegin
CoordinateSystem "start"
TransformBegin
  ConcatTransform [ 2 0 0 0  0 2 0 0  0 0 2 0  0 0 0 1 ]
  ReverseOrientation
  AreaLightSource "diffuse" "spectrum L" [ 400 1 700 2 ] "float scale" 3
  Shape "sphere"
TransformEnd
CoordSysTransform "camera"
Shape "curve" "point3 P" [ 0 0 0 1 1 1 2 2 2 3 3 3 ]
MakeNamedMedium "fog" "string type" "homogeneous"
Attribute "shape" "float radius" 2
Option "bool disablepixeljitter" true
)",
    // loopsubdiv: a closed tetrahedron at 2 levels, an open (boundary) fan at the default level,
    // and one at level 0; textures built from each other; named spectra.
    R"(LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" 40 "float lensradius" 0.05 "float focaldistance" 4
  "float screenwindow" [ -1 1 -0.75 0.75 ] "float shutteropen" 0 "float shutterclose" 0.5
Film "rgb" "integer xresolution" 32 "integer yresolution" 24 "float iso" 400
  "float exposuretime" 1
Option "bool disablepixeljitter" true
Option "string rendercoordsys" "world"
ColorSpace "srgb"
WorldBegin
Texture "c" "spectrum" "constant" "rgb value" [ 0.2 0.5 0.8 ]
Texture "f" "float" "constant" "float value" 0.25
Texture "s" "spectrum" "scale" "texture tex" "c" "float scale" 2
Texture "fs" "float" "scale" "texture tex" "f" "texture scale" "f"
Texture "m" "spectrum" "mix" "texture tex1" "s" "rgb tex2" [ 1 0 0 ] "texture amount" "fs"
Texture "mf" "float" "mix" "float tex1" 0.1 "float tex2" 0.9 "float amount" 0.3
Material "diffuse" "texture reflectance" "m"
Shape "loopsubdiv" "integer levels" 2
  "point3 P" [ 1 1 1  1 -1 -1  -1 1 -1  -1 -1 1 ] "integer indices" [ 0 1 2  0 3 1  0 2 3  1 3 2 ]
Material "conductor" "spectrum eta" "metal-Cu-eta" "spectrum k" "metal-Cu-k"
  "texture roughness" "mf"
Shape "loopsubdiv" "point3 P" [ 0 0 0  1 0 0  1 1 0  0 1 0  -1 0.5 0 ]
  "integer indices" [ 0 1 2  0 2 3  0 3 4 ]
Material "dielectric" "spectrum eta" "glass-BK7"
Shape "loopsubdiv" "integer levels" 0 "point3 P" [ 0 0 1  1 0 1  0 1 1 ] "integer indices" [ 0 1 2 ]
LightSource "distant" "spectrum L" "stdillum-D65" "point3 to" [ 0 -1 0 ]
AttributeBegin
  AreaLightSource "diffuse" "spectrum L" "stdillum-F4"
  Shape "sphere" "float radius" 0.1
AttributeEnd
)",
    // An image texture (refused: the fuzz targets read no files) after named-spectrum materials.
    R"(Camera "perspective" "float lensradius" 0 "float focaldistance" 1e6
Film "rgb" "float iso" 100
WorldBegin
MakeNamedMaterial "gold" "string type" "conductor" "spectrum eta" "metal-Au-eta"
  "spectrum k" "metal-Au-k"
MakeNamedMaterial "silver" "string type" "conductor" "spectrum eta" "metal-Ag-eta"
  "spectrum k" "metal-Ag-k" "float uroughness" 0.1 "float vroughness" 0.2
Texture "img" "spectrum" "imagemap" "string filename" "wood.png" "string encoding" "linear"
  "float scale" 0.5
Texture "s" "spectrum" "scale" "texture tex" "img" "float scale" 0.5
Texture "m" "spectrum" "mix" "texture tex1" "img" "texture tex2" "s" "float amount" 0.5
)",
    // A plymesh that is refused (no file access) and a non-manifold loopsubdiv.
    R"(WorldBegin
Shape "loopsubdiv" "integer levels" 1
  "point3 P" [ 0 0 0  1 0 0  0 1 0  0 -1 0  0 0 1 ] "integer indices" [ 0 1 2  1 0 3  0 1 4 ]
Shape "plymesh" "string filename" "mesh.ply.gz"
)",
};

const char* kJsonSeeds[] = {
    R"({
  // every kind of field, and no reference to another file
  "camera": {"position": [0.5, 0.5, 2.4], "target": [0.5, 0.5, 0], "up": [0, 1, 0], "fov": 38},
  "film": {"width": 64, "height": 48},
  "materials": {
    "white": {"albedo": [0.73, 0.73, 0.73]},
    "lamp": {"albedo": [0, 0, 0], "emission": [17, 12, 4], "two_sided": true},
    "brass": {"type": "conductor", "eta": [0.44, 0.53, 1.09], "k": [3.7, 2.8, 1.9], "roughness": 0.2},
    "red": {"type": "plastic", "albedo": [0.6, 0.1, 0.1], "roughness": 0.05, "ior": 1.5}
  },
  "shapes": [
    {"type": "box", "min": [0, 0, 0], "max": [1, 1, 1], "inward": true, "skip": ["+z", "-x"], "material": "white"},
    {"type": "quad", "origin": [0.4, 0.999, 0.4], "edge1": [0.2, 0, 0], "edge2": [0, 0, 0.2], "material": "lamp"},
    {"type": "triangle", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "material": "brass",
     "transform": {"scale": 0.1, "rotate": {"axis": [0, 1, 0], "angle": 30}, "translate": [0.5, 0, 0.5]}},
    {"type": "sphere", "center": [0.3, 0.15, 0.7], "radius": 0.15, "subdivisions": 2,
     "material": {"type": "plastic", "albedo": [0.6, 0.1, 0.1], "roughness": 0.05}},
    {"type": "box", "min": [2, 0, 0], "max": [3, 1, 1], "material": "red",
     "transform": {"matrix": [[1, 0, 0, 0], [0, 2, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}}
  ],
  "lights": [
    {"type": "directional", "direction": [-1, 0.9, -0.45], "irradiance": [9, 8, 6.5]},
    {"type": "point", "position": [0.5, 0.8, 0.5], "intensity": [0.5, 0.5, 0.5]}
  ],
  "sky": {"type": "dome", "triangles": 512, "radiance": [0.75, 0.97, 1.5], "up": [0, 0, 1],
          "radius_scale": 4, "full_sphere": true}
})",
    R"({"shapes": [{"type": "quad", "origin": [0, 0, 0], "edge1": [1, 0, 0], "edge2": [0, 1, 0],
  "material": {"emission": [1, 1, 1]}}], /* a comment */ "film": {"width": 8, "height": 8}})",
};

// An OBJ and its MTL (after fuzz::kMtlSeparator): every statement rll reads, and the index forms
// (v, v/vt, v//vn, v/vt/vn, negative).
const char* kObjSeed = R"(# hand-written seed
mtllib fuzz.mtl
o thing
g group1
s 1
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0 1.0
v 0.5 0.5 1 0.2 0.3 0.4
vt 0 0
vt 1 0
vt 1 1 0
vn 0 0 1
vn 0 1 0
usemtl white
f 1 2 3
f 1/1 3/3 4/2
f 1//1 2//1 5//2
f 2/2/1 3/3/1 5/1/2 4/1/1
usemtl lamp
f -5 -4 -3
l 1 2
p 3
)";
const char* kMtlSeed = R"(newmtl white
Kd 0.7
Ks 0.1 0.1 0.1
Ns 20
illum 2
newmtl lamp
Kd 0 0 0
Ke 5 4 3
d 1
Ni 1.5
)";

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: rll_fuzz_seeds DIR\n");
    return 2;
  }
  try {
    const fs::path dir = argv[1];
    for (const char* f : {"ply", "gltf", "pbrt", "json", "obj", "gzip", "exr", "image"})
      fs::create_directories(dir / f);
    Scene s = small_scene();
    Mesh tri;
    tri.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    tri.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    tri.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    tri.triangles = {{0, 1, 2}, {0, 2, 3}};
    write(dir / "ply/ascii.ply", ply_bytes(tri, PlyEncoding::Ascii));
    write(dir / "ply/little.ply", ply_bytes(tri, PlyEncoding::BinaryLittleEndian));
    write(dir / "ply/big.ply", ply_bytes(tri, PlyEncoding::BinaryBigEndian));
    Mesh plain;
    plain.positions = s.mesh.positions;
    plain.triangles = s.mesh.triangles;
    write(dir / "ply/scene.ply", ply_bytes(plain, PlyEncoding::Ascii));
    // gzip-compressed PLY (the fuzz target inflates input that begins with gzip's magic bytes):
    // one member, and a file cut in two members (concatenated members are one file).
    write(dir / "ply/little.ply.gz", gzip(ply_bytes(tri, PlyEncoding::BinaryLittleEndian)));
    const std::string ascii = ply_bytes(tri, PlyEncoding::Ascii);
    write(dir / "ply/ascii-two-members.ply.gz",
          gzip(ascii.substr(0, ascii.size() / 2)) + gzip(ascii.substr(ascii.size() / 2)));
    // The gzip target: the same members, and a header followed by more than it declares.
    write(dir / "gzip/little.ply.gz", gzip(ply_bytes(tri, PlyEncoding::BinaryLittleEndian)));
    write(dir / "gzip/ascii-two-members.ply.gz",
          gzip(ascii.substr(0, ascii.size() / 2)) + gzip(ascii.substr(ascii.size() / 2)));
    write(dir / "gzip/big-endian.ply.gz", gzip(ply_bytes(tri, PlyEncoding::BinaryBigEndian), 9));
    write(dir / "gzip/overlong.ply.gz", gzip(ply_bytes(tri, PlyEncoding::BinaryLittleEndian) +
                                             std::string(size_t(1) << 16, '\0')));
    // EXR: an image as textures and references are written, and a share with its attributes
    // and sample counts.
    Image image(5, 3);
    for (size_t i = 0; i < image.pixel_count(); ++i)
      image[i] = Rgb(float(i), 0.5f, 1e-3f * float(i));
    write_image(dir / "exr/image.exr", image);
    ExrFile share;
    share.image = image;
    share.attributes = {{"rll.share", "seed 1 spp 4"}, {"rll.scene", "builtin:cornell-box"}};
    share.counts.assign(image.pixel_count(), 4);
    write_exr(dir / "exr/share.exr", share);
    // Images: each format stb_image reads that stb_image_write writes, in grey, RGB and RGBA
    // (an HDR of 8 pixels or more a row is run-length coded).
    for (const char* format : {"png", "jpg", "bmp", "tga", "hdr"})
      for (int channels : {1, 3, 4})
        write(dir / fmt::format("image/seed-{}.{}", channels, format),
              encoded_image(format, 9, 5, channels));
    const fs::path gltf = dir / "gltf/scene.gltf";
    save_gltf_scene(s, gltf);
    write(dir / "gltf/scene.glb", glb_of(read_text_file(gltf)));
    for (size_t i = 0; i < std::size(kPbrtSeeds); ++i)
      write(dir / fmt::format("pbrt/seed{}.pbrt", i), kPbrtSeeds[i]);
    for (size_t i = 0; i < std::size(kJsonSeeds); ++i)
      write(dir / fmt::format("json/seed{}.json", i), kJsonSeeds[i]);
    const std::string separator(fuzz::kMtlSeparator);
    write(dir / "obj/hand.obj", kObjSeed + separator + kMtlSeed);
    // rll's own writer: the JSON it writes names its OBJ, whose mtllib is renamed to the name
    // the fuzz target serves the MTL by.
    const fs::path saved = dir / "obj/saved-tmp";
    fs::create_directories(saved);
    save_json_scene(s, saved / "scene.json");
    write(dir / "json/saved.json", read_text_file(saved / "scene.json"));
    std::string obj = read_text_file(saved / "scene.obj");
    if (size_t at = obj.find("mtllib scene.mtl"); at != std::string::npos)
      obj.replace(at, 16, "mtllib fuzz.mtl");
    write(dir / "obj/saved.obj", obj + separator + read_text_file(saved / "scene.mtl"));
    fs::remove_all(saved);
  } catch (const Error& e) {
    std::fprintf(stderr, "rll_fuzz_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
