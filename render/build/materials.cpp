// render — scene building: one Material per Material or MakeNamedMaterial directive, with
// pbrt-v3's parameters and defaults.
#include "pbrt/parser.h"
#include "render/build/builder.h"
#include "render/error.h"
#include "render/fourier.h"
#include "render/subsurface.h"

namespace cmam::render::build_detail {

// A material's microfacet roughness along u and v, "uroughness" and "vroughness" (or one
// "roughness" for both): `m.roughness` and `m.vroughness`, anisotropic when they differ. An absent
// one falls back as in pbrt-v3: uber's u on "roughness" and its v on u, metal's each on
// "roughness"; substrate has no "roughness" (pbrt-v3 reports it unused), each of its two
// defaulting to `def`.
void Builder::rough_inputs(const Entity& e, const TextureScope& s, float def, RoughFallback f,
                           Material& m) {
    const bool has_u = e.params.find("uroughness"), has_v = e.params.find("vroughness");
    if (f == RoughFallback::Substrate) {
        if (const pbrt::Param* r = e.params.find("roughness")) {
            warn(r->loc,
                 "\"roughness\" is not a parameter of substrate (pbrt-v3 ignores it; "
                 "its roughness is \"uroughness\" and \"vroughness\"); ignored");
            (void)float_input(e, s, "roughness", def);
        }
    } else if (!has_u && !has_v) {
        m.roughness = m.vroughness = float_input(e, s, "roughness", def);
        return;
    }
    const TexInput r = f == RoughFallback::Substrate ? TexInput{-1, Rgb(def)}
                                                     : float_input(e, s, "roughness", def);
    const TexInput u = has_u ? float_input(e, s, "uroughness", def) : r;
    const TexInput v =
        has_v ? float_input(e, s, "vroughness", def) : (f == RoughFallback::Uber ? u : r);
    m.roughness = u;
    m.vroughness = v;
    m.anisotropic = u.node != v.node || (u.node < 0 && !(u.value.r == v.value.r));
}

void Builder::matte_material(const pbrt::MaterialDesc& d, Material& m) {
    m.type = Material::Type::Matte;
    m.kd = spectrum_input(d.entity, d.scope, "Kd", Rgb(0.5f));
    m.sigma = float_input(d.entity, d.scope, "sigma", 0);
}

void Builder::mirror_material(const pbrt::MaterialDesc& d, Material& m) {
    m.type = Material::Type::Mirror;
    m.kr = spectrum_input(d.entity, d.scope, "Kr", Rgb(0.9f));
}

void Builder::glass_material(const pbrt::MaterialDesc& d, Material& m) {
    const Entity& e = d.entity;
    const TextureScope& s = d.scope;
    m.type = Material::Type::Glass;
    m.kr = spectrum_input(e, s, "Kr", Rgb(1));
    m.kt = spectrum_input(e, s, "Kt", Rgb(1));
    const char* eta = e.params.find("eta") ? "eta" : "index";
    m.eta = float_input(e, s, eta, 1.5f, true);
    // pbrt-v3's glass has "uroughness" and "vroughness" (0: smooth), and no "roughness".
    m.roughness = float_input(e, s, "uroughness", 0);
    m.vroughness = float_input(e, s, "vroughness", 0);
    m.anisotropic = m.roughness.node != m.vroughness.node ||
                    (m.roughness.node < 0 && !(m.roughness.value.r == m.vroughness.value.r));
    m.remap_roughness = e.params.get_bool("remaproughness", true);
}

void Builder::plastic_material(const pbrt::MaterialDesc& d, Material& m) {
    const Entity& e = d.entity;
    const TextureScope& s = d.scope;
    m.type = Material::Type::Plastic;
    m.kd = spectrum_input(e, s, "Kd", Rgb(0.25f));
    m.ks = spectrum_input(e, s, "Ks", Rgb(0.25f));
    m.roughness = m.vroughness = float_input(e, s, "roughness", 0.1f);
    m.remap_roughness = e.params.get_bool("remaproughness", true);
}

// pbrt-v3's uber: a diffuse lobe, a microfacet lobe (with a dielectric Fresnel term from air to
// its eta), and specular reflection and transmission with dielectric Fresnel (glass's).
void Builder::uber_material(const pbrt::MaterialDesc& d, Material& m) {
    const Entity& e = d.entity;
    const TextureScope& s = d.scope;
    m.type = Material::Type::Uber;
    m.kd = spectrum_input(e, s, "Kd", Rgb(0.25f));
    m.ks = spectrum_input(e, s, "Ks", Rgb(0.25f));
    m.kr = spectrum_input(e, s, "Kr", Rgb(0));
    m.kt = spectrum_input(e, s, "Kt", Rgb(0));
    rough_inputs(e, s, 0.1f, RoughFallback::Uber, m);
    m.remap_roughness = e.params.get_bool("remaproughness", true);
    const char* eta = e.params.find("eta") ? "eta" : "index";
    m.eta = float_input(e, s, eta, 1.5f, true);
    if (const auto* op = e.params.find("opacity")) {
        // pbrt-v3's opacity: every lobe times it, and the rest passed straight through (a
        // specular transmission of index 1, in the Bsdf's one specular transmission: where the
        // uber has its own, Kr or Kt, the opacity is left out, with a warning). (Opaque, 1 1 1,
        // is pbrt-v3's default and what published scenes give.)
        const TexInput opacity = spectrum_input(e, s, "opacity", Rgb(1));
        const bool opaque = opacity.node < 0 && opacity.value.r == 1 && opacity.value.g == 1 &&
                            opacity.value.b == 1;
        const auto black = [](const TexInput& in) { return in.node < 0 && in.value.is_black(); };
        if (!opaque && black(m.kr) && black(m.kt))
            m.opacity = opacity;
        else if (!opaque)
            warn(op->loc,
                 "uber \"opacity\" ignored beside its specular Kr or Kt: cmam renders the "
                 "material opaque");
    }
}

// pbrt-v3's substrate: a Fresnel-blended glossy coat over a diffuse base (FresnelBlend).
void Builder::substrate_material(const pbrt::MaterialDesc& d, Material& m) {
    const Entity& e = d.entity;
    const TextureScope& s = d.scope;
    m.type = Material::Type::Substrate;
    m.kd = spectrum_input(e, s, "Kd", Rgb(0.5f));
    m.ks = spectrum_input(e, s, "Ks", Rgb(0.5f));
    rough_inputs(e, s, 0.1f, RoughFallback::Substrate, m);
    m.remap_roughness = e.params.get_bool("remaproughness", true);
}

// pbrt-v3's translucent: plastic's parameters (and defaults), each lobe reflecting "reflect" and
// transmitting "transmit" (kept in kr and kt).
void Builder::translucent_material(const pbrt::MaterialDesc& d, Material& m) {
    plastic_material(d, m);
    m.type = Material::Type::Translucent;
    m.kr = spectrum_input(d.entity, d.scope, "reflect", Rgb(0.5f));
    m.kt = spectrum_input(d.entity, d.scope, "transmit", Rgb(0.5f));
}

// A conductor: a microfacet lobe with the Fresnel term of a conductor of index eta + i k
// (pbrt-v3: copper by default).
void Builder::metal_material(const pbrt::MaterialDesc& d, Material& m) {
    const Entity& e = d.entity;
    const TextureScope& s = d.scope;
    m.type = Material::Type::Metal;
    m.eta = spectrum_input(e, s, "eta", Rgb(0.2004f, 0.9240f, 1.1022f));
    m.k = spectrum_input(e, s, "k", Rgb(3.9129f, 2.4528f, 2.1421f));
    rough_inputs(e, s, 0.01f, RoughFallback::Metal, m);
    m.remap_roughness = e.params.get_bool("remaproughness", true);
}

void Builder::no_material(const pbrt::MaterialDesc& d, Material& m) {
    m.type = Material::Type::None;
}

void Builder::mix_material(const pbrt::MaterialDesc& d, Material& m) {
    const Entity& e = d.entity;
    m.type = Material::Type::Mix;
    m.amount = spectrum_input(e, d.scope, "amount", Rgb(0.5f));
    for (int k = 0; k < 2; ++k) {
        const std::string param = "namedmaterial" + std::to_string(k + 1);
        const auto* p = e.params.find(param);
        if (!p) throw SceneError(e.loc, "mix needs a \"string " + param + "\" parameter");
        const std::string name = e.params.get_string(param, "");
        m.mix[k] = d.mix[k];
        if (d.mix[k] < 0)
            warn(p->loc, "named material " + in_quotes(name) +
                             " is not defined here; the default matte is used in the mix");
    }
}

// pbrt-v3's tabulated BSDF, its file read once however many materials name it. A file that
// cannot be read (pbrt-v3 renders such a material black) gives a warning with the reason, and
// the material is rendered as matte with its Kd, as the materials cmam does not render.
void Builder::fourier_material(const pbrt::MaterialDesc& d, Material& m) {
    const Entity& e = d.entity;
    auto as_matte = [&](const pbrt::FileLoc& loc, const std::string& why) {
        warn(loc, why + "; the material is rendered as \"matte\"" +
                      (e.params.find("Kd") ? " with its Kd" : ""));
        m.type = Material::Type::Matte;
        m.kd = spectrum_input(e, d.scope, "Kd", Rgb(0.5f));
    };
    const pbrt::Param* file = e.params.find("bsdffile");
    const std::string name = e.params.get_string("bsdffile", "");
    if (!file) return as_matte(e.loc, "material \"fourier\" has no \"string bsdffile\"");
    const std::string path = pbrt::resolve_path(m_desc.base_dir, file->loc, name);
    // Each file is read once: a table, or the reason it could not be read.
    if (const auto e = m_fourier_errors.find(path); e != m_fourier_errors.end())
        return as_matte(file->loc, e->second);
    std::shared_ptr<const FourierTable>& table = m_fourier[path];
    if (!table) {
        try {
            table = std::make_shared<const FourierTable>(read_fourier_table(path));
        } catch (const RenderError& err) {
            m_fourier.erase(path);
            return as_matte(file->loc, m_fourier_errors[path] = err.what());
        }
    }
    m.type = Material::Type::Fourier;
    m.fourier = table;
}

// pbrt-v3's "hair": its absorption from "sigma_a", else from "color" (the colour after multiple
// scattering), else from the melanin concentrations "eumelanin" and "pheomelanin" (1.3 and 0 when
// none is given); "eta" 1.55, "beta_m" and "beta_n" 0.3, "alpha" 2 degrees.
void Builder::hair_material(const pbrt::MaterialDesc& d, Material& m) {
    const Entity& e = d.entity;
    const TextureScope& s = d.scope;
    m.type = Material::Type::Hair;
    const bool sigma_a = e.params.find("sigma_a"), colour = e.params.find("color");
    if (sigma_a) {
        m.hair_absorption = Material::HairAbsorption::SigmaA;
        m.hair_sigma_a = spectrum_input(e, s, "sigma_a", Rgb(0));
        if (colour) {
            warn(loc_of(e, "color"),
                 "material \"hair\": \"color\" is ignored since \"sigma_a\" "
                 "is given, as pbrt-v3 ignores it");
            (void)spectrum_input(e, s, "color", Rgb(0));
        }
    } else if (colour) {
        m.hair_absorption = Material::HairAbsorption::Colour;
        m.hair_colour = spectrum_input(e, s, "color", Rgb(0));
    } else {
        m.hair_absorption = Material::HairAbsorption::Concentration;
        if (e.params.find("eumelanin") || e.params.find("pheomelanin")) {
            m.eumelanin = float_input(e, s, "eumelanin", 0);
            m.pheomelanin = float_input(e, s, "pheomelanin", 0);
        }
    }
    m.eta = float_input(e, s, "eta", 1.55f, true);
    m.beta_m = float_input(e, s, "beta_m", 0.3f);
    m.beta_n = float_input(e, s, "beta_n", 0.3f);
    m.hair_alpha = float_input(e, s, "alpha", 2);
}

// pbrt-v3's "disney" (algorithms.md §24): "color", "metallic", "eta", "roughness",
// "speculartint", "anisotropic", "sheen", "sheentint", "clearcoat", "clearcoatgloss",
// "spectrans", "thin", "flatness", "difftrans", with pbrt-v3's defaults. Its subsurface
// scattering ("scatterdistance") is not rendered: with a warning, it is its diffuse lobe.
void Builder::disney_material(const pbrt::MaterialDesc& d, Material& m) {
    const Entity& e = d.entity;
    const TextureScope& s = d.scope;
    m.type = Material::Type::Disney;
    m.kd = spectrum_input(e, s, "color", Rgb(0.5f));
    m.metallic = float_input(e, s, "metallic", 0);
    m.eta = float_input(e, s, "eta", 1.5f);
    m.roughness = float_input(e, s, "roughness", 0.5f);
    m.specular_tint = float_input(e, s, "speculartint", 0);
    m.disney_anisotropic = float_input(e, s, "anisotropic", 0);
    m.sheen = float_input(e, s, "sheen", 0);
    m.sheen_tint = float_input(e, s, "sheentint", 0.5f);
    m.clearcoat = float_input(e, s, "clearcoat", 0);
    m.clearcoat_gloss = float_input(e, s, "clearcoatgloss", 1);
    m.thin = e.params.get_bool("thin", false);
    m.flatness = float_input(e, s, "flatness", 0);
    m.diff_trans = float_input(e, s, "difftrans", 1);
    m.spec_trans = float_input(e, s, "spectrans", 0);
    if (e.params.find("scatterdistance")) {
        const TexInput sd = spectrum_input(e, s, "scatterdistance", Rgb(0));
        if (sd.node >= 0 || !sd.value.is_black())
            warn(loc_of(e, "scatterdistance"),
                 "material \"disney\": subsurface scattering (\"scatterdistance\") is "
                 "rendered as its diffuse lobe");
    }
}

// What pbrt-v3's "subsurface" and "kdsubsurface" share: a glass's BSDF (Kr, Kt, its index as a
// plain float, default 1.33, and its roughness), the scale, and the profile's table for g and eta.
void Builder::subsurface_common(const pbrt::MaterialDesc& d, Material& m) {
    const Entity& e = d.entity;
    const TextureScope& s = d.scope;
    m.kr = spectrum_input(e, s, "Kr", Rgb(1));
    m.kt = spectrum_input(e, s, "Kt", Rgb(1));
    const double eta = finite_float(e, "eta", 1.33);
    if (!(eta > 0)) throw SceneError(loc_of(e, "eta"), "eta must be positive");
    m.eta = TexInput{-1, Rgb(static_cast<float>(eta))};
    m.roughness = float_input(e, s, "uroughness", 0);
    m.vroughness = float_input(e, s, "vroughness", 0);
    m.anisotropic = m.roughness.node != m.vroughness.node ||
                    (m.roughness.node < 0 && !(m.roughness.value.r == m.vroughness.value.r));
    m.remap_roughness = e.params.get_bool("remaproughness", true);
    m.sss_scale = static_cast<float>(finite_float(e, "scale", 1));
    if (m.sss_scale < 0) throw SceneError(loc_of(e, "scale"), "scale must not be negative");
}

// The profile table for phase asymmetry g and index eta, computed once for each pair.
namespace {
std::shared_ptr<const BssrdfTable> table_for(
    std::map<std::pair<float, float>, std::shared_ptr<const BssrdfTable>>& tables, float g,
    float eta, int threads) {
    auto& t = tables[{g, eta}];
    if (!t) t = BssrdfTable::beam_diffusion(g, eta, threads);
    return t;
}
}  // namespace

// pbrt-v3's "subsurface": absorption and scattering coefficients given ("sigma_a", "sigma_s",
// pbrt-v3's defaults in mm^-1) or measured ones by name (reduced scattering: g is then 0, as in
// pbrt-v3), times "scale".
void Builder::subsurface_material(const pbrt::MaterialDesc& d, Material& m) {
    const Entity& e = d.entity;
    const TextureScope& s = d.scope;
    m.type = Material::Type::Subsurface;
    subsurface_common(d, m);
    Rgb sigma_a(.0011f, .0024f, .014f), sigma_s(2.55f, 3.21f, 3.77f);
    float g = static_cast<float>(finite_float(e, "g", 0));
    if (const std::string name = e.params.get_string("name", ""); !name.empty()) {
        if (measured_scattering(name, sigma_a, sigma_s))
            g = 0;
        else
            warn(loc_of(e, "name"), "unknown measured medium " + in_quotes(name) +
                                        "; sigma_a and sigma_s take their defaults where not "
                                        "given, as in pbrt-v3");
    }
    if (!(std::abs(g) < 1)) throw SceneError(loc_of(e, "g"), "g must be in (-1, 1)");
    m.sss_sigma_a = spectrum_input(e, s, "sigma_a", sigma_a);
    m.sss_sigma_s = spectrum_input(e, s, "sigma_s", sigma_s);
    m.bssrdf = table_for(m_bssrdf_tables, g, m.eta.value.r, m_opts.threads);
}

// pbrt-v3's "kdsubsurface": the coefficients whose profile reflects "Kd" (default 0.5) with mean
// free path "mfp" (default 1), times "scale".
void Builder::kd_subsurface_material(const pbrt::MaterialDesc& d, Material& m) {
    const Entity& e = d.entity;
    const TextureScope& s = d.scope;
    m.type = Material::Type::KdSubsurface;
    subsurface_common(d, m);
    m.kd = spectrum_input(e, s, "Kd", Rgb(0.5f));
    m.mfp = spectrum_input(e, s, "mfp", Rgb(1));
    const float g = static_cast<float>(finite_float(e, "g", 0));
    if (!(std::abs(g) < 1)) throw SceneError(loc_of(e, "g"), "g must be in (-1, 1)");
    m.bssrdf = table_for(m_bssrdf_tables, g, m.eta.value.r, m_opts.threads);
}

// pbrt-v3 renders a material it does not know as matte, with a warning; so does cmam.
Material Builder::unrendered_material(const pbrt::MaterialDesc& d) {
    const Entity& e = d.entity;
    Material m;
    m.type = Material::Type::Matte;
    m.kd = spectrum_input(e, d.scope, "Kd", Rgb(0.5f));
    warn(e.loc, "material " + in_quotes(e.type) + " is rendered as \"matte\"" +
                    (e.params.find("Kd") ? " with its Kd" : "") +
                    " (cmam renders matte, mirror, glass, plastic, uber, metal, substrate, "
                    "translucent, fourier, hair, disney, subsurface, kdsubsurface and mix)");
    return m;  // its other parameters are not read: no warning for each
}

Material Builder::material(const pbrt::MaterialDesc& d) {
    static constexpr TypeBuilder<MaterialBuild> kMaterials[] = {
        {"matte", &Builder::matte_material},
        {"mirror", &Builder::mirror_material},
        {"glass", &Builder::glass_material},
        {"plastic", &Builder::plastic_material},
        {"uber", &Builder::uber_material},
        {"substrate", &Builder::substrate_material},
        {"translucent", &Builder::translucent_material},
        {"metal", &Builder::metal_material},
        {"fourier", &Builder::fourier_material},
        {"hair", &Builder::hair_material},
        {"disney", &Builder::disney_material},
        {"subsurface", &Builder::subsurface_material},
        {"kdsubsurface", &Builder::kd_subsurface_material},
        {"none", &Builder::no_material},
        {"", &Builder::no_material},
        {"mix", &Builder::mix_material}};
    const Entity& e = d.entity;
    const MaterialBuild build = find_builder(kMaterials, e.type);
    if (!build) return unrendered_material(d);
    Material m;
    (this->*build)(d, m);
    if (e.params.find("type")) e.params.get_string("type", "");
    if (e.params.find("bumpmap")) m.bump = float_input(e, d.scope, "bumpmap", 0);
    e.params.check_unused("material " + in_quotes(e.type), m_warn, {});
    return m;
}

}  // namespace cmam::render::build_detail
