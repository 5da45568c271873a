// render — scene building: point, spot, distant, infinite, goniometric and projection
// lights, and the images they read.
#include <cmath>
#include <numbers>

#include "pbrt/parser.h"
#include "render/build/builder.h"
#include "render/image_io.h"

namespace cmam::render::build_detail {

// A light's "mapname" image, read as pbrt-v3 reads light images: its values as stored, an 8-bit
// file's bytes over 255 with no sRGB decoding (pbrt-v3's infinite, goniometric and projection
// lights read the file with ReadImage, which decodes nothing; only image textures have "gamma").
texture::Image Builder::load_light_map(const std::string& path) {
    return load_texture(path, false, false, 1.0f, texture::WrapMode::Repeat);
}

std::shared_ptr<const texture::FilteredTexture> Builder::light_image(const Entity& e,
                                                                     const pbrt::Param& p) {
    const std::string path =
        pbrt::resolve_path(m_desc.base_dir, p.loc, e.params.get_string("mapname", ""));
    try {
        auto read = take_read_ahead(m_read_light_images, path);
        return std::make_shared<const texture::FilteredTexture>(read ? std::move(read->image)
                                                                     : load_light_map(path));
    } catch (const RenderError& err) {
        throw SceneError(p.loc, err.what());
    }
}

// The linear part of the light's transform's inverse (directions from world to light).
std::array<float, 9> Builder::light_from_world(const Entity& e, const Mat4& world_from_light) {
    const Mat4 inv = inverse_or_error(world_from_light, e.loc, "the light's transform is singular");
    std::array<float, 9> lw{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) lw[3 * i + j] = float(inv.m[i][j]);
    return lw;
}

// pbrt-v3's infinite light image: a lat-long map in the light's frame, read as its imagemap
// reads images (8-bit files decoded from sRGB); theta = 0 is the file's top row.
std::shared_ptr<const EnvironmentMap> Builder::environment_map(const Entity& e,
                                                               const pbrt::Param& p,
                                                               const Mat4& world_from_light) {
    auto env =
        std::make_shared<EnvironmentMap>(light_image(e, p), light_from_world(e, world_from_light));
    if (m_opts.filter) env->set_filter({*m_opts.filter});
    return env;
}

// pbrt-v3's "scale" of a light: the factor of its intensity or radiance.
Rgb Builder::light_scale(const Entity& e) {
    Rgb scale(1);
    if (auto sc = e.params.get_rgb("scale")) scale = to_rgb(finite_values(e, "scale", *sc));
    return scale;
}

// The light's intensity or radiance `name` (1 when not given) times its scale.
Rgb Builder::light_intensity(const Entity& e, const char* name, const Rgb& scale) {
    auto v = e.params.get_rgb(name);
    return (v ? to_rgb(finite_values(e, name, *v)) : Rgb(1)) * scale;
}

void Builder::point_light(const pbrt::LightDesc& d, const Rgb& scale, Light& l) {
    const Entity& e = d.entity;
    l.type = Light::Type::Point;
    l.intensity = light_intensity(e, "I", scale);
    l.position = to_vec(d.world_from_light.apply_point(finite_point(e, "from", {0, 0, 0})));
}

void Builder::spot_light(const pbrt::LightDesc& d, const Rgb& scale, Light& l) {
    const Entity& e = d.entity;
    const Mat4& m = d.world_from_light;
    l.type = Light::Type::Spot;
    l.intensity = light_intensity(e, "I", scale);
    auto from = finite_point(e, "from", {0, 0, 0});
    auto to = finite_point(e, "to", {0, 0, 1});
    // pbrt-v3 names the falloff "conedeltaangle"; "conedelta" is accepted too, for scenes
    // written for earlier cmam versions, with a warning: pbrt-v3 ignores it (and takes 5).
    const bool old_name = e.params.find("conedelta") && !e.params.find("conedeltaangle");
    const char* delta_name = old_name ? "conedelta" : "conedeltaangle";
    if (old_name)
        warn(loc_of(e, "conedelta"),
             "light \"spot\": \"conedelta\" is read as the falloff (cmam's earlier name for "
             "\"conedeltaangle\"); pbrt-v3 does not know it and would take the default, 5 degrees");
    double cone = finite_float(e, "coneangle", 30), delta = finite_float(e, delta_name, 5);
    l.position = to_vec(m.apply_point(from));
    Vec3 axis = to_vec(m.apply_vector({to[0] - from[0], to[1] - from[1], to[2] - from[2]}));
    if (length(axis) == 0) throw SceneError(e.loc, "spot light \"from\" and \"to\" coincide");
    l.direction = normalize(axis);
    l.cos_total = float(std::cos(cone * std::numbers::pi / 180));
    l.cos_falloff_start = float(std::cos((cone - delta) * std::numbers::pi / 180));
}

void Builder::distant_light(const pbrt::LightDesc& d, const Rgb& scale, Light& l) {
    const Entity& e = d.entity;
    l.type = Light::Type::Distant;
    l.intensity = light_intensity(e, "L", scale);
    auto from = finite_point(e, "from", {0, 0, 0});
    auto to = finite_point(e, "to", {0, 0, 1});
    Vec3 w = to_vec(
        d.world_from_light.apply_vector({from[0] - to[0], from[1] - to[1], from[2] - to[2]}));
    if (length(w) == 0) throw SceneError(e.loc, "distant light \"from\" and \"to\" coincide");
    l.direction = normalize(w);
}

void Builder::infinite_light(const pbrt::LightDesc& d, const Rgb& scale, Light& l) {
    const Entity& e = d.entity;
    l.type = Light::Type::Infinite;
    l.intensity = light_intensity(e, "L", scale);
    if (const auto* mp = e.params.find("mapname")) {
        l.env = environment_map(e, *mp, d.world_from_light);
        // Escaping rays filter the map over their ray differentials' footprint, with
        // the image textures' filter (EWA unless overridden); other footprint sources
        // point-sample it as pbrt-v3 does.
        l.env_footprint = !m_opts.lod || *m_opts.lod == FootprintMethod::Differentials;
        if (l.env_footprint) m_scene->footprint_methods.add(FootprintMethod::Differentials);
    }
    e.params.get_int("samples",
                     1);  // pbrt-v3's sample count hint; one sample per lookup here
}

// "goniometric" and "projection": a point light at the light's origin whose intensity follows
// an image.
void Builder::image_light(const pbrt::LightDesc& d, const Rgb& scale, Light& l) {
    const Entity& e = d.entity;
    const Mat4& m = d.world_from_light;
    l.type = e.type == "goniometric" ? Light::Type::Goniometric : Light::Type::Projection;
    l.intensity = light_intensity(e, "I", scale);
    l.position = to_vec(m.apply_point({0, 0, 0}));
    auto img = std::make_shared<LightImage>();
    img->kind =
        e.type == "goniometric" ? LightImage::Kind::Goniometric : LightImage::Kind::Projection;
    img->light_from_world = light_from_world(e, m);
    if (e.type == "projection") {
        const double fov = finite_float(e, "fov", 45);
        if (!(fov > 0 && fov < 180))
            throw SceneError(loc_of(e, "fov"), "fov must be in (0, 180) degrees");
        img->tan_half_fov = float(std::tan(fov * std::numbers::pi / 360));
    }
    if (const auto* mp = e.params.find("mapname")) {
        img->image = light_image(e, *mp);
        const auto& im = img->image->image();
        const float aspect = float(im.width()) / float(im.height());
        if (aspect > 1) {
            img->screen[0] = -aspect, img->screen[1] = aspect;
        } else {
            img->screen[2] = -1 / aspect, img->screen[3] = 1 / aspect;
        }
        l.image = img;
    } else if (e.type == "projection") {
        l.image = img;  // without an image: 1 inside the square screen's frustum
    }
}

void Builder::light(const pbrt::LightDesc& d) {
    static constexpr TypeBuilder<LightBuild> kLights[] = {
        {"point", &Builder::point_light},       {"spot", &Builder::spot_light},
        {"distant", &Builder::distant_light},   {"infinite", &Builder::infinite_light},
        {"goniometric", &Builder::image_light}, {"projection", &Builder::image_light}};
    const Entity& e = d.entity;
    Light l;
    const Rgb scale = light_scale(e);
    finite_transform(d.world_from_light, e.loc, "light");
    (this->*builder_for(kLights, e, "light"))(d, scale, l);
    // A delta light needs one shadow ray; the others take nsamples under directlighting.
    // (pbrt-v3's goniometric light has no fov, but scenes give it; pbrt-v3 warns too.)
    if (l.type == Light::Type::Infinite) l.samples = light_samples(e);
    e.params.check_unused("light " + in_quotes(e.type), m_warn, {"nsamples", "conedelta", "fov"});
    m_scene->lights.push_back(l);
}

}  // namespace cmam::render::build_detail
