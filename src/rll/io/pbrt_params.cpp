// The pbrt reader's parameter lists (see pbrt_internal.h).
#include <array>
#include <cctype>

#include "rll/io/pbrt_internal.h"
#include "rll/io/spectra.h"

namespace rll::pbrt {

bool is_numeric_type(const std::string& t) {
  return t != "bool" && t != "string" && t != "texture";
}

const std::set<std::string_view>& pbrt_directives() {
  static const std::set<std::string_view> names = {"Accelerator",
                                                   "ActiveTransform",
                                                   "AreaLightSource",
                                                   "Attribute",
                                                   "AttributeBegin",
                                                   "AttributeEnd",
                                                   "Camera",
                                                   "ColorSpace",
                                                   "ConcatTransform",
                                                   "CoordinateSystem",
                                                   "CoordSysTransform",
                                                   "Film",
                                                   "Identity",
                                                   "Import",
                                                   "Include",
                                                   "Integrator",
                                                   "LightSource",
                                                   "LookAt",
                                                   "MakeNamedMaterial",
                                                   "MakeNamedMedium",
                                                   "Material",
                                                   "MediumInterface",
                                                   "NamedMaterial",
                                                   "ObjectBegin",
                                                   "ObjectEnd",
                                                   "ObjectInstance",
                                                   "Option",
                                                   "PixelFilter",
                                                   "ReverseOrientation",
                                                   "Rotate",
                                                   "Sampler",
                                                   "Scale",
                                                   "Shape",
                                                   "Texture",
                                                   "Transform",
                                                   "TransformBegin",
                                                   "TransformEnd",
                                                   "TransformTimes",
                                                   "Translate",
                                                   "WorldBegin",
                                                   "WorldEnd"};
  return names;
}

std::vector<Param> PbrtReader::param_list(const std::string& what) {
  std::vector<Param> params;
  while (const Token* p = peek()) {
    if (!p->quoted) break;
    Token decl = *take();
    std::string_view rest = decl.text, type, name, extra;
    if (!next_token(rest, type) || !next_token(rest, name) || next_token(rest, extra))
      syntax(decl, fmt::format("expected a parameter declaration \"TYPE NAME\", got \"{}\"",
                               printable(decl.text)));
    Param par;
    par.type = std::string(type);
    par.name = std::string(name);
    par.line = decl.line;
    if (std::find(std::begin(kParamTypes), std::end(kParamTypes), par.type) ==
        std::end(kParamTypes))
      syntax(decl, fmt::format("unknown parameter type '{}'", printable(par.type)));
    for (const auto& q : params)
      if (q.name == par.name)
        syntax(decl, fmt::format("parameter '{}' given twice", printable(par.name)));
    Token v = expect_token(decl, "a parameter value");
    auto add_value = [&](const Token& t) {
      if (t.quoted) {
        par.strings.push_back(unescape(t.text));
      } else if (t.text == "true" || t.text == "false") {
        par.strings.push_back(std::string(t.text));
      } else if (is_directive(t) || t.text == "[" || t.text == "]") {
        syntax(t, fmt::format("parameter '{}' has a bad value '{}'", printable(par.name),
                              printable(t.text)));
      } else if (par.type == "integer") {
        par.integers.push_back(integer(t, what, par.name));
      } else {
        par.numbers.push_back(number(t));
      }
    };
    if (!v.quoted && v.text == "[") {
      for (;;) {
        Token t = expect_token(decl, "]");
        if (!t.quoted && t.text == "]") break;
        add_value(t);
      }
    } else {
      add_value(v);
    }
    const bool numeric = is_numeric_type(par.type);
    if (par.type == "spectrum" && par.numbers.empty() && par.strings.size() == 1) {
      // a named spectrum or a file
    } else if (numeric ? !par.strings.empty() : (!par.numbers.empty() || !par.integers.empty())) {
      syntax(decl,
             fmt::format("parameter \"{} {}\" has values of the wrong kind", par.type, par.name));
    }
    if (par.type == "bool")
      for (const auto& s : par.strings)
        if (s != "true" && s != "false")
          syntax(decl, fmt::format("bool parameter '{}' must be true or false (got \"{}\")",
                                   par.name, s));
    if (par.numbers.empty() && par.integers.empty() && par.strings.empty())
      syntax(decl, fmt::format("parameter '{}' has no value", par.name));
    params.push_back(std::move(par));
  }
  return params;
}

std::optional<Rgb> PbrtReader::Params::get_spectrum(const char* name) const {
  const Param* p = find(name);
  if (!p) return std::nullopt;
  if (p->type == "rgb" || p->type == "color") {
    if (p->numbers.size() != 3) bad(*p, fmt::format("needs 3 values (got {})", p->numbers.size()));
    Rgb c(float(p->numbers[0]), float(p->numbers[1]), float(p->numbers[2]));
    if (min_component(c) < 0) bad(*p, "must not be negative");
    return c;
  }
  if (p->type == "blackbody") {
    const double t = one_number(*p);
    const Rgb c = t > 0 ? blackbody_rgb(t) : Rgb(0);
    if (!(t > 0) || !is_finite(c) || !(luminance(c) > 0))
      bad(*p, "needs a positive temperature at which a blackbody glows");
    return c;
  }
  if (p->type == "float") {  // pbrt-v4 accepts a float for a spectrum in some places
    const float v = float(one_number(*p));
    if (v < 0) bad(*p, "must not be negative");  // as an rgb value
    return Rgb(v);
  }
  if (p->type != "spectrum") bad(*p, "must be of type rgb, spectrum or blackbody");
  if (!p->strings.empty()) {
    const std::string& s = p->strings[0];
    if (auto c = named_spectrum_rgb(s)) return c;
    if (s.rfind("stdillum-", 0) == 0 || s.rfind("illum-", 0) == 0) return Rgb(1);
    if (s == "glass-BK7") return Rgb(1.5168f);
    if (s.rfind("glass-", 0) == 0) return Rgb(1.5f);
    // pbrt-v4 reads any other name as a spectrum file, which rll does not read: an existing
    // file keeps the parameter's default (a warning); a name that is neither is an error, as in
    // pbrt-v4.
    if (!m_r.m_policy.read_files || !unreadable_reason(m_r.resolve(s)).empty())
      bad(*p, fmt::format("names spectrum \"{}\", which is neither a named spectrum rll knows "
                          "({}, glass-*, stdillum-*, illum-*) nor a file",
                          printable(s), named_spectrum_names()));
    m_r.warn("spectrum " + s,
             fmt::format("{}: {}: spectrum file \"{}\" is not read by rll; parameter '{}' keeps "
                         "its default",
                         m_r.where(m_at.file, p->line), m_what, printable(s), p->name));
    return std::nullopt;
  }
  if (p->numbers.size() < 2 || p->numbers.size() % 2 != 0) bad(*p, "needs wavelength-value pairs");
  double sum = 0;
  for (size_t i = 1; i < p->numbers.size(); i += 2) sum += p->numbers[i];
  const float mean = to_float(sum / double(p->numbers.size() / 2));
  return Rgb(std::max(0.0f, mean));
}

}  // namespace rll::pbrt
