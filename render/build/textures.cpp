// render — scene building: texture inputs, pbrt-v3's texture mappings, image loading, and
// one TextureNode per Texture directive.
#include <cmam/texture/ewa.h>

#include <algorithm>
#include <filesystem>
#include <sstream>

#include "pbrt/parser.h"
#include "render/build/builder.h"
#include "render/image_io.h"

namespace cmam::render::build_detail {

TexInput Builder::spectrum_input(const Entity& e, const TextureScope& scope,
                                 const std::string& name, Rgb def) {
    if (auto ref = e.params.get_texture(name)) {
        auto it = scope.spectrum_textures.find(ref->name);
        if (it == scope.spectrum_textures.end())
            throw SceneError(ref->loc,
                             "spectrum texture " + in_quotes(ref->name) + " is not defined");
        return {it->second, {}};
    }
    if (auto c = e.params.get_rgb(name)) return {-1, to_rgb(finite_values(e, name, *c))};
    return {-1, def};
}

TexInput Builder::float_input(const Entity& e, const TextureScope& scope, const std::string& name,
                              float def, bool positive) {
    if (auto ref = e.params.get_texture(name)) {
        auto it = scope.float_textures.find(ref->name);
        if (it == scope.float_textures.end())
            throw SceneError(ref->loc, "float texture " + in_quotes(ref->name) + " is not defined");
        return {it->second, {}};
    }
    return {-1, Rgb(float(finite_float(e, name, def, positive)))};
}

// pbrt-v3's 2-D texture mappings ("mapping": uv, spherical, cylindrical, planar).
void Builder::uv_mapping(const Entity& e, const pbrt::TextureDesc& t, TextureNode* n) {
    std::string mapping = e.params.get_string("mapping", "uv");
    if (mapping == "uv") {
        n->su = float(e.params.get_float("uscale", 1));
        n->sv = float(e.params.get_float("vscale", 1));
        n->du = float(e.params.get_float("udelta", 0));
        n->dv = float(e.params.get_float("vdelta", 0));
    } else if (mapping == "spherical" || mapping == "cylindrical") {
        n->mapping = mapping == "spherical" ? TextureNode::Mapping::Spherical
                                            : TextureNode::Mapping::Cylindrical;
        texture_space(e, t, n);
    } else if (mapping == "planar") {
        n->mapping = TextureNode::Mapping::Planar;
        n->v1 = to_vec(finite_point(e, "v1", {1, 0, 0}));
        n->v2 = to_vec(finite_point(e, "v2", {0, 1, 0}));
        n->du = float(finite_float(e, "udelta", 0));
        n->dv = float(finite_float(e, "vdelta", 0));
    } else {
        const auto* p = e.params.find("mapping");
        throw SceneError(p ? p->loc : e.loc,
                         "unknown texture mapping " + in_quotes(mapping) +
                             " (expected \"uv\", \"spherical\", \"cylindrical\" or "
                             "\"planar\")");
    }
}

// World -> texture space: the inverse of the transform where the texture was declared.
void Builder::texture_space(const Entity& e, const pbrt::TextureDesc& t, TextureNode* n) {
    finite_transform(t.world_from_texture, e.loc, "texture");
    const Mat4 inv =
        inverse_or_error(t.world_from_texture, e.loc, "the texture's transform is singular");
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 4; ++j) n->texture_from_world[4 * i + j] = float(inv.m[i][j]);
}

Builder::ImageRequest Builder::image_request(const Entity& e, bool is_float) const {
    const auto* fp = e.params.find("filename");
    if (!fp) throw SceneError(e.loc, "imagemap texture needs a \"string filename\" parameter");
    ImageRequest r;
    r.is_float = is_float;
    r.name = e.params.get_string("filename", "");
    r.path = pbrt::resolve_path(m_desc.base_dir, fp->loc, r.name);
    std::string wrap_name = e.params.get_string("wrap", "repeat");
    auto wrap = texture::parse_wrap_mode(wrap_name);
    if (!wrap || *wrap == texture::WrapMode::Mirror)
        throw SceneError(e.params.find("wrap")->loc,
                         "unknown wrap mode " + in_quotes(wrap_name) +
                             " (expected \"repeat\", \"black\" or \"clamp\")");
    r.wrap = *wrap;
    r.scale = float(finite_float(e, "scale", 1));
    if (e.params.find("gamma")) r.gamma = e.params.get_bool("gamma", true);
    // The same file under the same settings is loaded once. A path the file system cannot
    // resolve (too long a name, say) keys as written; reading it then fails with the reason.
    std::error_code ec;
    std::string canonical = std::filesystem::weakly_canonical(r.path, ec).string();
    if (ec) canonical = r.path;
    r.key = canonical + "|" + (is_float ? "f" : "s") + "|" +
            std::string(texture::to_string(r.wrap)) + "|" + std::to_string(r.scale) + "|" +
            (r.gamma ? (*r.gamma ? "1" : "0") : "default");
    return r;
}

const texture::FilteredTexture* Builder::load_image(const Entity& e, bool is_float) {
    const ImageRequest r = image_request(e, is_float);
    const auto* fp = e.params.find("filename");
    const std::string& name = r.name;
    auto it = m_scene->images.find(r.key);
    if (it != m_scene->images.end()) return it->second.get();
    texture::Image level0;
    std::size_t bad = 0;  // texel values that are not finite
    try {
        if (auto read = take_read_ahead(m_read_images, r.key)) {
            level0 = std::move(read->image);
            bad = read->bad;
        } else {
            level0 = load_texture(r.path, is_float, r.gamma, r.scale, r.wrap, nullptr, true, &bad);
        }
    } catch (const RenderError& err) {
        throw SceneError(fp->loc, err.what());
    }
    // Float files may hold NaN or infinite texels; every filter reading one returns one, and the
    // samples it reaches are taken as black. pbrt-v3 reads them silently; cmam says so here.
    if (bad)
        warn(fp->loc, in_quotes(name) + " has " + std::to_string(bad) +
                          (bad == 1 ? " texel value that is not a finite number"
                                    : " texel values that are not finite numbers") +
                          " (NaN or infinite); the samples whose lookups read " +
                          (bad == 1 ? "it" : "them") + " are taken as black");
    auto img = std::make_unique<texture::FilteredTexture>(std::move(level0));
    const texture::FilteredTexture* ptr = img.get();
    m_scene->images.emplace(r.key, std::move(img));
    return ptr;
}

// A texture's input `name`: a float texture or constant in a float texture, a spectrum one in a
// spectrum texture.
TexInput Builder::texture_input(const pbrt::TextureDesc& t, const std::string& name, float def) {
    return t.is_float ? float_input(t.entity, t.scope, name, def)
                      : spectrum_input(t.entity, t.scope, name, Rgb(def));
}

void Builder::image_texture(const pbrt::TextureDesc& t, TextureNode& n) {
    const Entity& e = t.entity;
    n.kind = TextureNode::Kind::Image;
    uv_mapping(e, t, &n);
    n.image = load_image(e, t.is_float);
    if (m_opts.untextured) {
        const texture::Texel& mean = n.image->image().mean();
        n.kind = TextureNode::Kind::Constant;
        n.constant =
            n.image->image().channels() == 1 ? Rgb(mean[0]) : Rgb(mean[0], mean[1], mean[2]);
    }
    // pbrt-v3: EWA unless "trilinear" is true; "maxanisotropy" bounds EWA's eccentricity.
    n.filter.kind = e.params.get_bool("trilinear", false) ? texture::FilterKind::Trilinear
                                                          : texture::FilterKind::Ewa;
    n.filter.max_aniso = e.params.get_float("maxanisotropy", 8);
    // cmam's extensions (pbrt-v3 warns that it does not use them):
    // "string filter" and "string lod".
    if (const auto* fp = e.params.find("filter")) {
        std::string f = e.params.get_string("filter", "");
        auto k = texture::parse_filter(f);
        if (!k)
            throw SceneError(fp->loc, "unknown filter " + in_quotes(f) + " (expected " +
                                          texture::filter_names("\"") + ")");
        n.filter.kind = *k;
    }
    if (const auto* lp = e.params.find("lod")) {
        std::string l = e.params.get_string("lod", "");
        auto k = parse_footprint_method(l);
        if (!k)
            throw SceneError(lp->loc, "unknown lod " + in_quotes(l) + " (expected " +
                                          kFootprintMethodNames.list("\"") + ")");
        n.lod = *k;
    }
    if (m_opts.filter) n.filter.kind = *m_opts.filter;
    if (m_opts.lod) n.lod = *m_opts.lod;
    // With ray differentials, trilinear measures the footprint as pbrt-v3 does.
    n.filter.pbrt_trilinear_width = n.lod == FootprintMethod::Differentials;
    if (!(n.filter.max_aniso >= 1))
        throw SceneError(e.params.find("maxanisotropy")->loc, "maxanisotropy must be at least 1");
    if (n.filter.max_aniso > texture::kEwaMaxAnisotropy) {
        std::ostringstream m;
        m << "maxanisotropy " << n.filter.max_aniso << " is above cmam's limit of "
          << texture::kEwaMaxAnisotropy << ", which is used instead";
        warn(e.params.find("maxanisotropy")->loc, m.str());
    }
}

void Builder::constant_texture(const pbrt::TextureDesc& t, TextureNode& n) {
    n.kind = TextureNode::Kind::Constant;
    n.constant = texture_input(t, "value", 1).value;
}

void Builder::checkerboard_texture(const pbrt::TextureDesc& t, TextureNode& n) {
    const Entity& e = t.entity;
    if (e.params.get_int("dimension", 2) == 3) {
        n.kind = TextureNode::Kind::Checkerboard3D;
        texture_space(e, t, &n);
        n.tex1 = texture_input(t, "tex1", 1);
        n.tex2 = texture_input(t, "tex2", 0);
        return;
    }
    n.kind = TextureNode::Kind::Checkerboard;
    int dim = e.params.get_int("dimension", 2);
    if (dim != 2)
        throw SceneError(e.params.find("dimension")->loc,
                         "checkerboard dimension must be 2 or 3, got " + std::to_string(dim));
    uv_mapping(e, t, &n);
    n.tex1 = texture_input(t, "tex1", 1);
    n.tex2 = texture_input(t, "tex2", 0);
    std::string aa = e.params.get_string("aamode", "closedform");
    n.closed_form = aa == "closedform";
    // --filter area: the closed form's box becomes the footprint's own parallelogram (§5.4).
    if (m_opts.filter) n.filter.kind = *m_opts.filter;
    if (m_opts.untextured) {  // the mean of the two inputs (constants only)
        if (n.tex1.node < 0 && n.tex2.node < 0) {
            n.kind = TextureNode::Kind::Constant;
            n.constant = (n.tex1.value + n.tex2.value) * 0.5f;
        } else {
            n.kind = TextureNode::Kind::Mix;
            n.amount = {-1, Rgb(0.5f)};
        }
    }
    if (m_opts.lod) n.lod = *m_opts.lod;
    if (aa != "closedform" && aa != "none")
        throw SceneError(
            e.params.find("aamode")->loc,
            "unknown aamode " + in_quotes(aa) + " (expected \"closedform\" or \"none\")");
}

void Builder::scale_texture(const pbrt::TextureDesc& t, TextureNode& n) {
    n.kind = TextureNode::Kind::Scale;
    n.tex1 = texture_input(t, "tex1", 1);
    n.tex2 = texture_input(t, "tex2", 1);
}

void Builder::mix_texture(const pbrt::TextureDesc& t, TextureNode& n) {
    n.kind = TextureNode::Kind::Mix;
    n.tex1 = texture_input(t, "tex1", 0);
    n.tex2 = texture_input(t, "tex2", 1);
    n.amount = float_input(t.entity, t.scope, "amount", 0.5f);
}

void Builder::bilerp_texture(const pbrt::TextureDesc& t, TextureNode& n) {
    const Entity& e = t.entity;
    n.kind = TextureNode::Kind::Bilerp;
    uv_mapping(e, t, &n);
    const char* names[4] = {"v00", "v01", "v10", "v11"};
    const float defs[4] = {0, 1, 0, 1};
    for (int k = 0; k < 4; ++k) {
        if (t.is_float)
            n.corners[k] = Rgb(float(finite_float(e, names[k], defs[k])));
        else if (auto c = e.params.get_rgb(names[k]))
            n.corners[k] = to_rgb(finite_values(e, names[k], *c));
        else
            n.corners[k] = Rgb(defs[k]);
    }
}

void Builder::uv_texture(const pbrt::TextureDesc& t, TextureNode& n) {
    n.kind = TextureNode::Kind::Uv;
    uv_mapping(t.entity, t, &n);
    if (t.is_float)
        warn(t.entity.loc, "pbrt-v3 has no float \"uv\" texture; cmam gives its s coordinate");
}

void Builder::dots_texture(const pbrt::TextureDesc& t, TextureNode& n) {
    n.kind = TextureNode::Kind::Dots;
    uv_mapping(t.entity, t, &n);
    // tex1 inside the dots, tex2 outside. pbrt-v3 hands its "inside" to the texture's outsideDot
    // and its "outside" to insideDot (the constructor takes them in the other order), so its
    // dots show "outside" (default 0) on a background of "inside" (default 1); scenes written
    // for it were composed that way, and cmam renders them so.
    n.tex1 = texture_input(t, "outside", 0);
    n.tex2 = texture_input(t, "inside", 1);
}

// pbrt-v3's noise textures: "fbm", "wrinkled", "windy" and "marble".
void Builder::noise_texture(const pbrt::TextureDesc& t, TextureNode& n) {
    const Entity& e = t.entity;
    n.kind = e.type == "fbm"        ? TextureNode::Kind::Fbm
             : e.type == "wrinkled" ? TextureNode::Kind::Wrinkled
             : e.type == "windy"    ? TextureNode::Kind::Windy
                                    : TextureNode::Kind::Marble;
    texture_space(e, t, &n);
    if (e.type != "windy") {
        n.octaves = std::clamp(e.params.get_int("octaves", 8), 0, 64);
        n.omega = float(finite_float(e, "roughness", 0.5));
    }
    if (e.type == "marble") {
        n.scale = float(finite_float(e, "scale", 1));
        n.variation = float(finite_float(e, "variation", 0.2));
        if (t.is_float)
            warn(e.loc,
                 "pbrt-v3 has no float \"marble\" texture; cmam gives the "
                 "luminance of its colour");
    }
    // Their octaves follow the footprint, as in pbrt-v3: ray differentials are traced.
    m_scene->footprint_methods.add(FootprintMethod::Differentials);
}

void Builder::texture(const pbrt::TextureDesc& t) {
    static constexpr TypeBuilder<TextureBuild> kClasses[] = {
        {"imagemap", &Builder::image_texture},
        {"checkerboard", &Builder::checkerboard_texture},
        {"constant", &Builder::constant_texture},
        {"scale", &Builder::scale_texture},
        {"mix", &Builder::mix_texture},
        {"bilerp", &Builder::bilerp_texture},
        {"uv", &Builder::uv_texture},
        {"dots", &Builder::dots_texture},
        {"fbm", &Builder::noise_texture},
        {"wrinkled", &Builder::noise_texture},
        {"windy", &Builder::noise_texture},
        {"marble", &Builder::noise_texture}};
    const Entity& e = t.entity;
    TextureNode n;
    n.is_float = t.is_float;
    const std::string what =
        std::string(t.is_float ? "float" : "spectrum") + " texture " + in_quotes(e.type);
    (this->*builder_for(kClasses, e, "texture class"))(t, n);
    // Non-uv mappings take their footprints from dP/dx and dP/dy (with cones, from the
    // cone's cross-section at the hit: FootprintProducers::at_hit, which the lod below enables).
    if (n.mapping != TextureNode::Mapping::Uv &&
        (n.kind == TextureNode::Kind::Image || n.kind == TextureNode::Kind::Checkerboard) &&
        n.lod == FootprintMethod::Differentials)
        m_scene->footprint_methods.add(FootprintMethod::Differentials);
    e.params.check_unused(what, m_warn);
    auto depth_of = [&](const TexInput& in) {
        return in.node >= 0 && std::size_t(in.node) < m_texture_depth.size()
                   ? m_texture_depth[std::size_t(in.node)]
                   : 0;
    };
    const int depth = 1 + std::max({depth_of(n.tex1), depth_of(n.tex2), depth_of(n.amount)});
    if (depth > kMaxTextureDepth)
        throw SceneError(e.loc, "texture " + in_quotes(t.name) + " nests " + std::to_string(depth) +
                                    " textures deep, beyond cmam's limit of " +
                                    std::to_string(kMaxTextureDepth));
    m_texture_depth.resize(m_scene->textures.size(), 1);
    m_texture_depth.push_back(depth);
    if (n.kind == TextureNode::Kind::Image ||
        (n.kind == TextureNode::Kind::Checkerboard && n.closed_form))
        m_scene->footprint_methods.add(n.lod);
    m_scene->textures.push_back(n);
}

}  // namespace cmam::render::build_detail
