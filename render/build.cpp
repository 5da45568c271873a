// render — turns a parsed pbrt-v3 description into a renderable Scene, with pbrt-v3's
// defaults and meanings, reporting unsupported input at its file location.
#include <cmam/texture/ewa.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>

#include "pbrt/parser.h"
#include "pbrt/ply.h"
#include "render/image_io.h"
#include "render/scene.h"
#include "render/tessellate.h"

namespace cmam::render {

using pbrt::Entity;
using pbrt::Mat4;
using pbrt::SceneError;
using pbrt::TextureScope;

namespace {

std::string q(const std::string& s) {
    return "\"" + s + "\"";
}

std::array<double, 12> to34(const Mat4& m) {
    std::array<double, 12> r{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 4; ++j) r[4 * i + j] = m.m[i][j];
    return r;
}

class Builder {
  public:
    Builder(const pbrt::SceneDesc& d, const BuildOptions& o, const pbrt::WarningSink& w)
        : m_desc(d), m_opts(o), m_warn(w) {}

    std::unique_ptr<Scene> run() {
        m_scene = std::make_unique<Scene>();
        m_scene->tags = m_opts.tags;
        m_scene->cmam = m_opts.cmam;
        // Each directive's problem is collected and building goes on, so that one run reports
        // every error it can find (up to pbrt::kMaxReportedErrors): a missing file does not hide
        // the next.
        std::vector<SceneError> errors;
        auto attempt = [&](auto&& build) {
            if (errors.size() >= pbrt::kMaxReportedErrors) return;
            try {
                build();
            } catch (const SceneError& e) {
                errors.push_back(e);
            }
        };
        attempt([&] { film(); });
        attempt([&] { camera(); });
        attempt([&] { sampler(); });
        attempt([&] { filter(); });
        attempt([&] { integrator(); });
        attempt([&] {
            if (m_desc.accelerator.given)
                m_desc.accelerator.params.check_unused("Accelerator", m_warn,
                                                       names_of(m_desc.accelerator));
        });
        // A texture, material or area light that fails keeps its index (a placeholder), so
        // that what names it is still checked.
        for (std::size_t i = 0; i < m_desc.textures.size(); ++i) {
            attempt([&] { texture(m_desc.textures[i]); });
            m_scene->textures.resize(i + 1);
        }
        for (const auto& m : m_desc.materials) {
            Material mat;
            attempt([&] { mat = material(m); });
            m_scene->materials.push_back(mat);
        }
        for (const auto& a : m_desc.area_lights) {
            Light l;
            attempt([&] { l = area_light(a); });
            m_area_lights.push_back(l);
        }
        for (const auto& s : m_desc.shapes) attempt([&] { shape(s, m_scene->primitives); });
        attempt([&] { instances(); });
        for (const auto& l : m_desc.lights) attempt([&] { light(l); });
        if (!errors.empty()) throw SceneError(errors);
        if (m_scene->lights.empty() && (!m_desc.shapes.empty() || !m_desc.instances.empty()) &&
            m_warn)
            m_warn(pbrt::format_warning(m_desc.camera.loc,
                                        "the scene has no lights; it will render black"));
        m_scene->commit();
        return std::move(m_scene);
    }

  private:
    const pbrt::SceneDesc& m_desc;
    BuildOptions m_opts;
    pbrt::WarningSink m_warn;
    std::unique_ptr<Scene> m_scene;
    std::map<std::string, std::unique_ptr<pbrt::PlyMesh>> m_ply;  // by resolved path
    std::vector<Light> m_area_lights;  // per AreaLightSource: what each shape in its scope emits
    bool m_light_samples = false;      // lights' nsamples are used (directlighting, "all")

    // Shadow rays per shading point for a light: its nsamples under pbrt-v3's directlighting
    // integrator, which reads them; 1 otherwise, as pbrt-v3's whitted and path take.
    int light_samples(const Entity& e) const {
        if (!m_light_samples || !e.params.find("nsamples")) return 1;
        return std::clamp(e.params.get_int("nsamples", 1), 1, 1 << 16);
    }

    void warn(const pbrt::FileLoc& loc, const std::string& msg) {
        if (m_warn) m_warn(pbrt::format_warning(loc, msg));
    }
    // Where a parameter was written, or the directive's location when it was not.
    static const pbrt::FileLoc& loc_of(const Entity& e, const std::string& name) {
        const pbrt::Param* p = e.params.find(name);
        return p ? p->loc : e.loc;
    }
    static std::vector<std::string> names_of(const Entity& e) {
        std::vector<std::string> n;
        for (const auto& p : e.params.params()) n.push_back(p.name);
        return n;
    }

    // Numbers the renderer uses must be finite in single precision (a NaN or infinite light,
    // material or shape parameter once rendered black without a word).
    static bool is_finite_float(double v) {
        return std::abs(v) <= std::numeric_limits<float>::max();
    }
    static double finite(const pbrt::FileLoc& loc, const std::string& name, double v,
                         bool positive = false) {
        if (!is_finite_float(v) || (positive && !(v > 0)))
            throw SceneError(loc, name + " must be a " + (positive ? "positive " : "") +
                                      "finite number, got " + pbrt::number_text(v));
        return v;
    }
    static double finite_float(const Entity& e, const std::string& name, double def,
                               bool positive = false) {
        return finite(loc_of(e, name), name, e.params.get_float(name, def), positive);
    }
    template <class Values>
    static const Values& finite_values(const Entity& e, const std::string& name,
                                       const Values& values) {
        for (double v : values)
            if (!is_finite_float(v))
                throw SceneError(loc_of(e, name), name + " values must be finite numbers, got " +
                                                      pbrt::number_text(v));
        return values;
    }
    // A shape's or light's transform: every entry finite (NaN or infinite transforms once gave
    // black images).
    // The inverse of `m`, or `message` at `loc` when m is singular.
    static Mat4 inverse_or_error(const Mat4& m, const pbrt::FileLoc& loc, const char* message) {
        try {
            return m.inverse();
        } catch (const SceneError&) {
            throw SceneError(loc, message);
        }
    }

    static void finite_transform(const Mat4& m, const pbrt::FileLoc& loc, const char* what) {
        for (const auto& row : m.m)
            for (double v : row)
                if (!is_finite_float(v))
                    throw SceneError(loc, std::string("the ") + what +
                                              "'s transform must be finite, got an entry of " +
                                              pbrt::number_text(v));
    }

    void film() {
        const Entity& e = m_desc.film;
        FilmSettings& f = m_scene->film;
        if (e.given && e.type != "image")
            throw SceneError(e.loc, "unsupported Film " + q(e.type) + " (supported: \"image\")");
        auto side = [&](const char* name, int def) {
            const int n = e.params.get_int(name, def);
            if (n < 1 || n > kMaxFilmSide)
                throw SceneError(loc_of(e, name), std::string(name) + " must be between 1 and " +
                                                      std::to_string(kMaxFilmSide) + ", got " +
                                                      std::to_string(n));
            return n;
        };
        f.xres = side("xresolution", 640);
        f.yres = side("yresolution", 480);
        const long long pixels = static_cast<long long>(f.xres) * f.yres;
        if (pixels > kMaxFilmPixels)
            throw SceneError(loc_of(e, "xresolution"), "a film of " + std::to_string(f.xres) + "x" +
                                                           std::to_string(f.yres) + " = " +
                                                           std::to_string(pixels) +
                                                           " pixels is above cmam's limit of " +
                                                           std::to_string(kMaxFilmPixels));
        f.filename = e.params.get_string("filename", "pbrt.exr");
        double cw[4] = {0, 1, 0, 1};
        if (auto c = e.params.get_floats("cropwindow")) {
            if (c->size() != 4)
                throw SceneError(e.params.find("cropwindow")->loc, "cropwindow needs 4 values");
            for (int i = 0; i < 4; ++i) {
                if (!std::isfinite((*c)[i]))
                    throw SceneError(e.params.find("cropwindow")->loc,
                                     "cropwindow values must be finite numbers, got " +
                                         pbrt::number_text((*c)[i]));
                cw[i] = std::clamp((*c)[i], 0.0, 1.0);
            }
        }
        f.x0 = static_cast<int>(std::ceil(f.xres * std::min(cw[0], cw[1])));
        f.x1 = static_cast<int>(std::ceil(f.xres * std::max(cw[0], cw[1])));
        f.y0 = static_cast<int>(std::ceil(f.yres * std::min(cw[2], cw[3])));
        f.y1 = static_cast<int>(std::ceil(f.yres * std::max(cw[2], cw[3])));
        if (f.width() <= 0 || f.height() <= 0)
            throw SceneError(e.params.find("cropwindow")->loc, "cropwindow selects no pixels");
        // pbrt-v3 multiplies every pixel by "scale" (radiance only, not AOVs).
        f.scale = static_cast<float>(finite_float(e, "scale", 1));
        e.params.check_unused("Film \"image\"", m_warn,
                              {"diagonal", "maxsampleluminance", "pixelbounds"});
    }

    void camera() {
        const Entity& e = m_desc.camera;
        if (!e.given) throw SceneError(m_desc.film.loc, "the scene has no Camera directive");
        if (e.type != "perspective" && e.type != "orthographic" && e.type != "environment")
            throw SceneError(e.loc, "unsupported Camera " + q(e.type) +
                                        " (supported: \"perspective\", \"orthographic\", "
                                        "\"environment\")");
        Camera& c = m_scene->camera;
        c.orthographic = e.type == "orthographic";
        c.environment = e.type == "environment";
        c.xres = m_scene->film.xres;
        c.yres = m_scene->film.yres;
        double frame = e.params.get_float("frameaspectratio", double(c.xres) / c.yres);
        if (!(frame > 0 && std::isfinite(frame)))
            throw SceneError(loc_of(e, "frameaspectratio"),
                             "frameaspectratio must be a positive finite number, got " +
                                 pbrt::number_text(frame));
        if (frame > 1) {
            c.screen[0] = float(-frame);
            c.screen[1] = float(frame);
            c.screen[2] = -1;
            c.screen[3] = 1;
        } else {
            c.screen[0] = -1;
            c.screen[1] = 1;
            c.screen[2] = float(-1 / frame);
            c.screen[3] = float(1 / frame);
        }
        if (auto sw = e.params.get_floats("screenwindow")) {
            if (sw->size() != 4)
                throw SceneError(e.params.find("screenwindow")->loc, "screenwindow needs 4 values");
            for (int i = 0; i < 4; ++i) {
                if (!(std::abs((*sw)[i]) <= std::numeric_limits<float>::max()))
                    throw SceneError(e.params.find("screenwindow")->loc,
                                     "screenwindow values must be finite numbers, got " +
                                         pbrt::number_text((*sw)[i]));
                c.screen[i] = float((*sw)[i]);
            }
        }
        double fov = c.orthographic ? 90 : e.params.get_float("fov", 90);
        double halffov = c.orthographic ? -1 : e.params.get_float("halffov", -1);
        if (halffov > 0) fov = 2 * halffov;
        if (!(fov > 0 && fov < 180))
            throw SceneError(loc_of(e, "fov"), "fov must be in (0, 180) degrees");
        c.tan_half_fov = c.orthographic ? 1.0f : float(std::tan(fov * std::numbers::pi / 360));
        if (e.params.get_float("lensradius", 0) != 0)
            warn(e.params.find("lensradius")->loc,
                 "lensradius ignored: cmam renders a pinhole camera");
        const Mat4 wc =
            inverse_or_error(m_desc.camera_from_world, e.loc, "the camera transform is singular");
        auto m = to34(wc);
        for (int i = 0; i < 12; ++i) c.world_from_camera[i] = float(m[i]);
        check_camera_rays(c, e.loc);
        e.params.check_unused("Camera " + q(e.type), m_warn,
                              {"focaldistance", "shutteropen", "shutterclose"});
    }

    // Embree takes rays whose origin and direction are finite and within kMaxRayCoordinate.
    // Camera rays are checked through the film's corners: the origin (orthographic) and the
    // direction before normalisation are affine in the raster position, so the corners bound
    // every other pixel's.
    static void check_camera_rays(const Camera& c, const pbrt::FileLoc& loc) {
        auto text = [](const Vec3& v) {
            return "(" + pbrt::number_text(v.x, 7) + ", " + pbrt::number_text(v.y, 7) + ", " +
                   pbrt::number_text(v.z, 7) + ")";
        };
        for (int corner = 0; corner < 4; ++corner) {
            const float px = corner & 1 ? float(c.xres) : 0, py = corner & 2 ? float(c.yres) : 0;
            Vec3 org, dir;
            c.generate_ray(px, py, &org, &dir);
            const std::string at = " at raster position (" + pbrt::number_text(px) + ", " +
                                   pbrt::number_text(py) + ")";
            for (float x : {org.x, org.y, org.z})
                if (!(std::abs(x) <= kMaxRayCoordinate))
                    throw SceneError(
                        loc, "camera rays start at " + text(org) + at +
                                 ", beyond cmam's limit of " +
                                 pbrt::number_text(kMaxRayCoordinate, 7) +
                                 " on coordinates (check the camera transform and screenwindow)");
            if (!(std::abs(length(dir) - 1) < 1e-3f))
                throw SceneError(loc, "camera rays have direction " + text(dir) + at +
                                          ", not a finite unit vector (check the camera "
                                          "transform, screenwindow and frameaspectratio)");
        }
    }

    void sampler() {
        const Entity& e = m_desc.sampler;
        SamplerSettings& s = m_scene->sampler;
        if (!e.given) {  // pbrt-v3's default: halton, 16 samples per pixel
            s.xsamples = s.ysamples = 4;
        } else if (e.type == "stratified") {
            s.xsamples = e.params.get_int("xsamples", 4);
            s.ysamples = e.params.get_int("ysamples", 4);
            s.jitter = e.params.get_bool("jitter", true);
            if (s.xsamples <= 0 || s.ysamples <= 0)
                throw SceneError(e.loc, "xsamples and ysamples must be positive");
            const long long spp = static_cast<long long>(s.xsamples) * s.ysamples;
            if (spp > kMaxSamplesPerPixel)
                throw SceneError(loc_of(e, "xsamples"),
                                 "xsamples x ysamples = " + std::to_string(s.xsamples) + "x" +
                                     std::to_string(s.ysamples) + " = " + std::to_string(spp) +
                                     " samples per pixel is above cmam's limit of " +
                                     std::to_string(kMaxSamplesPerPixel));
            e.params.check_unused("Sampler \"stratified\"", m_warn, {"dimensions", "pixelsamples"});
        } else if (e.type == "halton" || e.type == "random" || e.type == "sobol" ||
                   e.type == "02sequence" || e.type == "lowdiscrepancy" || e.type == "maxmindist") {
            int n = e.params.get_int("pixelsamples", 16);
            if (n <= 0) throw SceneError(e.loc, "pixelsamples must be positive");
            if (n > kMaxSamplesPerPixel)
                throw SceneError(loc_of(e, "pixelsamples"),
                                 "pixelsamples " + std::to_string(n) +
                                     " is above cmam's limit of " +
                                     std::to_string(kMaxSamplesPerPixel) + " samples per pixel");
            int k = std::max(1, static_cast<int>(std::lround(std::sqrt(double(n)))));
            s.xsamples = s.ysamples = k;
            // With --spp the count comes from there (set below), not from pixelsamples.
            const std::string count =
                m_opts.spp_override > 0
                    ? std::string(", as many as --spp asks for")
                    : " with " + std::to_string(k) + "x" + std::to_string(k) + " per pixel";
            warn(e.loc, "Sampler " + q(e.type) + " is rendered as \"stratified\" jittered samples" +
                            count);
            e.params.check_unused("Sampler " + q(e.type), m_warn, names_of(e));
        } else {
            throw SceneError(e.loc, "unknown Sampler " + q(e.type));
        }
        if (m_opts.spp_override > kMaxSamplesPerPixel)
            throw SceneError("--spp " + std::to_string(m_opts.spp_override) +
                             " is above cmam's limit of " + std::to_string(kMaxSamplesPerPixel));
        if (m_opts.spp_override > 0) {
            int k =
                std::max(1, static_cast<int>(std::lround(std::sqrt(double(m_opts.spp_override)))));
            s.xsamples = s.ysamples = k;
            s.jitter = k > 1;
        }
        // A row of the film holds every sample of its pixels at once (and sample numbers along a
        // row or column are ints), so the samples along the film's larger side are bounded too.
        const FilmSettings& f = m_scene->film;
        const long long side = std::max(f.xres, f.yres);
        const long long per_row = side * s.spp();
        if (per_row > kMaxSamplesPerRow)
            throw SceneError(
                m_opts.spp_override > 0 ? pbrt::FileLoc{} : e.loc,
                std::to_string(s.spp()) + " samples per pixel along " + std::to_string(side) +
                    " pixels (the film's larger side) = " + std::to_string(per_row) +
                    " samples, above cmam's limit of " + std::to_string(kMaxSamplesPerRow));
    }

    void filter() {
        const Entity& e = m_desc.filter;
        if (!e.given) return;
        if (e.type == "box") {
            double xw = e.params.get_float("xwidth", 0.5), yw = e.params.get_float("ywidth", 0.5);
            if (xw != 0.5 || yw != 0.5)
                warn(e.loc,
                     "box filter width other than 0.5 is rendered with width 0.5 (each sample "
                     "counts for its own pixel)");
            e.params.check_unused("PixelFilter \"box\"", m_warn);
        } else if (e.type == "gaussian" || e.type == "mitchell" || e.type == "sinc" ||
                   e.type == "triangle") {
            warn(e.loc, "PixelFilter " + q(e.type) + " is rendered as \"box\"");
            e.params.check_unused("PixelFilter", m_warn, names_of(e));
        } else {
            throw SceneError(e.loc, "unknown PixelFilter " + q(e.type));
        }
    }

    void integrator() {
        const Entity& e = m_desc.integrator;
        if (!e.given) {
            if (!m_desc.shapes.empty())
                warn(m_desc.camera.loc,
                     "no Integrator given: pbrt-v3 would path trace (\"path\"); cmam renders "
                     "\"whitted\"");
            return;
        }
        // pbrt-v3's directlighting is whitted's recursion with every light sampled nsamples
        // times ("all", its default) or one light chosen per point ("one": here each light
        // once, the same expectation).
        const bool direct = e.type == "directlighting";
        if (direct)
            m_light_samples = e.params.get_string("strategy", "all") == "all";
        else if (e.type != "whitted")
            warn(e.loc, "Integrator " + q(e.type) + " is rendered as \"whitted\"");
        if (const auto* p = e.params.find("maxdepth")) {
            const int depth = e.params.get_int("maxdepth", 5);
            m_scene->max_depth = std::min(depth, kMaxDepthLimit);
            if (depth > kMaxDepthLimit)
                warn(p->loc, "maxdepth " + std::to_string(depth) + " is above cmam's limit of " +
                                 std::to_string(kMaxDepthLimit) + ", which is used instead");
        }
        e.params.check_unused(
            "Integrator " + q(e.type), m_warn,
            e.type == "whitted" || direct ? std::vector<std::string>{"pixelbounds"} : names_of(e));
    }

    // --- textures ---------------------------------------------------------------------
    TexInput spectrum_input(const Entity& e, const TextureScope& scope, const std::string& name,
                            Rgb def) {
        if (auto ref = e.params.get_texture(name)) {
            auto it = scope.spectrum_textures.find(ref->name);
            if (it == scope.spectrum_textures.end())
                throw SceneError(ref->loc, "spectrum texture " + q(ref->name) + " is not defined");
            return {it->second, {}};
        }
        if (auto c = e.params.get_rgb(name)) return {-1, to_rgb(finite_values(e, name, *c))};
        return {-1, def};
    }
    TexInput float_input(const Entity& e, const TextureScope& scope, const std::string& name,
                         float def, bool positive = false) {
        if (auto ref = e.params.get_texture(name)) {
            auto it = scope.float_textures.find(ref->name);
            if (it == scope.float_textures.end())
                throw SceneError(ref->loc, "float texture " + q(ref->name) + " is not defined");
            return {it->second, {}};
        }
        return {-1, Rgb(float(finite_float(e, name, def, positive)))};
    }

    // pbrt-v3's 2-D texture mappings ("mapping": uv, spherical, cylindrical, planar).
    void uv_mapping(const Entity& e, const pbrt::TextureDesc& t, TextureNode* n) {
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
            n->v1 = to_vec(finite_values(e, "v1", e.params.get_point3("v1", {1, 0, 0})));
            n->v2 = to_vec(finite_values(e, "v2", e.params.get_point3("v2", {0, 1, 0})));
            n->du = float(finite_float(e, "udelta", 0));
            n->dv = float(finite_float(e, "vdelta", 0));
        } else {
            const auto* p = e.params.find("mapping");
            throw SceneError(p ? p->loc : e.loc,
                             "unknown texture mapping " + q(mapping) +
                                 " (expected \"uv\", \"spherical\", \"cylindrical\" or "
                                 "\"planar\")");
        }
    }
    // World -> texture space: the inverse of the transform where the texture was declared.
    void texture_space(const Entity& e, const pbrt::TextureDesc& t, TextureNode* n) {
        finite_transform(t.world_from_texture, e.loc, "texture");
        const Mat4 inv =
            inverse_or_error(t.world_from_texture, e.loc, "the texture's transform is singular");
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 4; ++j) n->texture_from_world[4 * i + j] = float(inv.m[i][j]);
    }

    const texture::FilteredTexture* load_image(const Entity& e, bool is_float) {
        const auto* fp = e.params.find("filename");
        if (!fp) throw SceneError(e.loc, "imagemap texture needs a \"string filename\" parameter");
        std::string name = e.params.get_string("filename", "");
        std::string path = pbrt::resolve_path(m_desc.base_dir, fp->loc, name);
        std::string wrap_name = e.params.get_string("wrap", "repeat");
        auto wrap = texture::parse_wrap_mode(wrap_name);
        if (!wrap || *wrap == texture::WrapMode::Mirror)
            throw SceneError(e.params.find("wrap")->loc,
                             "unknown wrap mode " + q(wrap_name) +
                                 " (expected \"repeat\", \"black\" or \"clamp\")");
        float scale = float(finite_float(e, "scale", 1));
        std::optional<bool> gamma;
        if (e.params.find("gamma")) gamma = e.params.get_bool("gamma", true);
        std::string key = std::filesystem::weakly_canonical(path).string() + "|" +
                          (is_float ? "f" : "s") + "|" + std::string(texture::to_string(*wrap)) +
                          "|" + std::to_string(scale) + "|" +
                          (gamma ? (*gamma ? "1" : "0") : "default");
        auto it = m_scene->images.find(key);
        if (it != m_scene->images.end()) return it->second.get();
        texture::Image level0;
        try {
            level0 = load_texture(path, is_float, gamma, scale, *wrap);
        } catch (const ImageIoError& err) {
            throw SceneError(fp->loc, err.what());
        }
        auto img = std::make_unique<texture::FilteredTexture>(std::move(level0));
        const texture::FilteredTexture* ptr = img.get();
        m_scene->images.emplace(key, std::move(img));
        return ptr;
    }

    void texture(const pbrt::TextureDesc& t) {
        const Entity& e = t.entity;
        TextureNode n;
        n.is_float = t.is_float;
        const std::string what =
            std::string(t.is_float ? "float" : "spectrum") + " texture " + q(e.type);
        auto input = [&](const std::string& name, float def) {
            return t.is_float ? float_input(e, t.scope, name, def)
                              : spectrum_input(e, t.scope, name, Rgb(def));
        };
        if (e.type == "imagemap") {
            n.kind = TextureNode::Kind::Image;
            uv_mapping(e, t, &n);
            n.image = load_image(e, t.is_float);
            if (m_opts.untextured) {
                const texture::Texel& mean = n.image->image().mean();
                n.kind = TextureNode::Kind::Constant;
                n.constant = n.image->image().channels() == 1 ? Rgb(mean[0])
                                                              : Rgb(mean[0], mean[1], mean[2]);
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
                    throw SceneError(fp->loc, "unknown filter " + q(f) + " (expected " +
                                                  texture::filter_names("\"") + ")");
                n.filter.kind = *k;
            }
            if (const auto* lp = e.params.find("lod")) {
                std::string l = e.params.get_string("lod", "");
                auto k = parse_footprint_method(l);
                if (!k)
                    throw SceneError(lp->loc, "unknown lod " + q(l) + " (expected " +
                                                  kFootprintMethodNames.list("\"") + ")");
                n.lod = *k;
            }
            if (m_opts.filter) n.filter.kind = *m_opts.filter;
            if (m_opts.lod) n.lod = *m_opts.lod;
            // With ray differentials, trilinear measures the footprint as pbrt-v3 does.
            n.filter.pbrt_trilinear_width = n.lod == FootprintMethod::Differentials;
            if (!(n.filter.max_aniso >= 1))
                throw SceneError(e.params.find("maxanisotropy")->loc,
                                 "maxanisotropy must be at least 1");
            if (n.filter.max_aniso > texture::kEwaMaxAnisotropy) {
                std::ostringstream m;
                m << "maxanisotropy " << n.filter.max_aniso << " is above cmam's limit of "
                  << texture::kEwaMaxAnisotropy << ", which is used instead";
                warn(e.params.find("maxanisotropy")->loc, m.str());
            }
        } else if (e.type == "constant") {
            n.kind = TextureNode::Kind::Constant;
            n.constant = input("value", 1).value;
        } else if (e.type == "checkerboard" && e.params.get_int("dimension", 2) == 3) {
            n.kind = TextureNode::Kind::Checkerboard3D;
            texture_space(e, t, &n);
            n.tex1 = input("tex1", 1);
            n.tex2 = input("tex2", 0);
        } else if (e.type == "checkerboard") {
            n.kind = TextureNode::Kind::Checkerboard;
            int dim = e.params.get_int("dimension", 2);
            if (dim != 2)
                throw SceneError(
                    e.params.find("dimension")->loc,
                    "checkerboard dimension must be 2 or 3, got " + std::to_string(dim));
            uv_mapping(e, t, &n);
            n.tex1 = input("tex1", 1);
            n.tex2 = input("tex2", 0);
            std::string aa = e.params.get_string("aamode", "closedform");
            n.closed_form = aa == "closedform";
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
                    "unknown aamode " + q(aa) + " (expected \"closedform\" or \"none\")");
        } else if (e.type == "scale") {
            n.kind = TextureNode::Kind::Scale;
            n.tex1 = input("tex1", 1);
            n.tex2 = input("tex2", 1);
        } else if (e.type == "mix") {
            n.kind = TextureNode::Kind::Mix;
            n.tex1 = input("tex1", 0);
            n.tex2 = input("tex2", 1);
            n.amount = float_input(e, t.scope, "amount", 0.5f);
        } else if (e.type == "bilerp") {
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
        } else if (e.type == "uv") {
            n.kind = TextureNode::Kind::Uv;
            uv_mapping(e, t, &n);
            if (t.is_float)
                warn(e.loc, "pbrt-v3 has no float \"uv\" texture; cmam gives its s coordinate");
        } else if (e.type == "dots") {
            n.kind = TextureNode::Kind::Dots;
            uv_mapping(e, t, &n);
            n.tex1 = input("inside", 1);
            n.tex2 = input("outside", 0);
        } else if (e.type == "fbm" || e.type == "wrinkled" || e.type == "windy" ||
                   e.type == "marble") {
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
            m_scene->needs_differentials = true;
        } else {
            throw SceneError(e.loc, "unsupported texture class " + q(e.type) +
                                        " (supported: \"imagemap\", \"checkerboard\", "
                                        "\"constant\", \"scale\", \"mix\", \"bilerp\", "
                                        "\"uv\", \"dots\", \"fbm\", \"wrinkled\", "
                                        "\"windy\", \"marble\")");
        }
        // Non-uv mappings take their footprints from dP/dx and dP/dy.
        if (n.mapping != TextureNode::Mapping::Uv &&
            (n.kind == TextureNode::Kind::Image || n.kind == TextureNode::Kind::Checkerboard) &&
            n.lod == FootprintMethod::Differentials)
            m_scene->needs_differentials = true;
        e.params.check_unused(what, m_warn);
        if (n.kind == TextureNode::Kind::Image ||
            (n.kind == TextureNode::Kind::Checkerboard && n.closed_form)) {
            if (n.lod == FootprintMethod::Differentials) m_scene->needs_differentials = true;
            if (n.lod == FootprintMethod::Cones || n.lod == FootprintMethod::ConesAniso)
                m_scene->needs_cones = true;
            if (n.lod == FootprintMethod::ConesAniso) m_scene->needs_cones_aniso = true;
            if (n.lod == FootprintMethod::Cmam) m_scene->uses_cmam = true;
        }
        m_scene->textures.push_back(n);
    }

    // --- materials ----------------------------------------------------------------------
    // pbrt-v3's "roughness", or the mean of "uroughness" and "vroughness" (cmam's microfacet
    // distribution is isotropic).
    TexInput rough_input(const Entity& e, const TextureScope& s, float def) {
        if (e.params.find("uroughness") || e.params.find("vroughness")) {
            TexInput u = float_input(e, s, "uroughness", def),
                     v = float_input(e, s, "vroughness", def);
            if (u.node < 0 && v.node < 0) return TexInput{-1, Rgb(0.5f * (u.value.r + v.value.r))};
            warn(e.loc, "textured uroughness/vroughness: uroughness is used for both");
            (void)e.params.get_float("roughness", def);
            return u;
        }
        return float_input(e, s, "roughness", def);
    }

    Material material(const pbrt::MaterialDesc& d) {
        const Entity& e = d.entity;
        const TextureScope& s = d.scope;
        Material m;
        const std::string& t = e.type;
        if (t == "matte") {
            m.type = Material::Type::Matte;
            m.kd = spectrum_input(e, s, "Kd", Rgb(0.5f));
            m.sigma = float_input(e, s, "sigma", 0);
        } else if (t == "mirror") {
            m.type = Material::Type::Mirror;
            m.kr = spectrum_input(e, s, "Kr", Rgb(0.9f));
        } else if (t == "glass") {
            m.type = Material::Type::Glass;
            m.kr = spectrum_input(e, s, "Kr", Rgb(1));
            m.kt = spectrum_input(e, s, "Kt", Rgb(1));
            const char* eta = e.params.find("eta") ? "eta" : "index";
            m.eta = float_input(e, s, eta, 1.5f, true);
            for (const char* r : {"uroughness", "vroughness"}) {
                TexInput rough = float_input(e, s, r, 0);
                if (rough.node >= 0 || rough.value.r != 0)
                    warn(e.params.find(r)->loc,
                         std::string(r) + " ignored: glass is rendered perfectly smooth");
            }
            e.params.get_bool("remaproughness", true);
        } else if (t == "plastic") {
            m.type = Material::Type::Plastic;
            m.kd = spectrum_input(e, s, "Kd", Rgb(0.25f));
            m.ks = spectrum_input(e, s, "Ks", Rgb(0.25f));
            m.roughness = float_input(e, s, "roughness", 0.1f);
            m.remap_roughness = e.params.get_bool("remaproughness", true);
        } else if (t == "uber") {
            // pbrt-v3's uber: a diffuse lobe, a microfacet lobe (plastic's), and specular
            // reflection and transmission with dielectric Fresnel (glass's).
            m.type = Material::Type::Uber;
            m.kd = spectrum_input(e, s, "Kd", Rgb(0.25f));
            m.ks = spectrum_input(e, s, "Ks", Rgb(0.25f));
            m.kr = spectrum_input(e, s, "Kr", Rgb(0));
            m.kt = spectrum_input(e, s, "Kt", Rgb(0));
            m.roughness = rough_input(e, s, 0);
            m.remap_roughness = e.params.get_bool("remaproughness", true);
            const char* eta = e.params.find("eta") ? "eta" : "index";
            m.eta = float_input(e, s, eta, 1.5f, true);
            if (const auto* op = e.params.find("opacity")) {
                warn(op->loc, "uber \"opacity\" ignored: cmam renders the material opaque");
                (void)spectrum_input(e, s, "opacity", Rgb(1));
            }
        } else if (t == "substrate" || t == "translucent") {
            // Approximated by plastic: substrate's Fresnel-blended glossy coat over a diffuse
            // base, and translucent's reflection (its transmission is not rendered).
            m.type = Material::Type::Plastic;
            m.kd = spectrum_input(e, s, "Kd", Rgb(t == "substrate" ? 0.5f : 0.25f));
            m.ks = spectrum_input(e, s, "Ks", Rgb(t == "substrate" ? 0.5f : 0.25f));
            m.roughness =
                t == "substrate" ? rough_input(e, s, 0.1f) : float_input(e, s, "roughness", 0.1f);
            m.remap_roughness = e.params.get_bool("remaproughness", true);
            if (t == "translucent") {
                (void)spectrum_input(e, s, "reflect", Rgb(0.5f));
                (void)spectrum_input(e, s, "transmit", Rgb(0.5f));
            }
            warn(e.loc, "material " + q(t) + " is rendered as \"plastic\" (" +
                            (t == "substrate" ? "its Fresnel blend approximated"
                                              : "no diffuse transmission") +
                            ")");
        } else if (t == "metal") {
            // A conductor: a microfacet lobe whose Fresnel term is Schlick's from the
            // normal-incidence reflectance of eta and k (pbrt-v3: copper by default).
            m.type = Material::Type::Metal;
            m.eta = spectrum_input(e, s, "eta", Rgb(0.2004f, 0.9240f, 1.1022f));
            m.k = spectrum_input(e, s, "k", Rgb(3.9129f, 2.4528f, 2.1421f));
            m.roughness = rough_input(e, s, 0.01f);
            m.remap_roughness = e.params.get_bool("remaproughness", true);
        } else if (t == "none" || t.empty()) {
            m.type = Material::Type::None;
        } else if (t == "mix") {
            m.type = Material::Type::Mix;
            m.amount = spectrum_input(e, s, "amount", Rgb(0.5f));
            for (int k = 0; k < 2; ++k) {
                const std::string param = "namedmaterial" + std::to_string(k + 1);
                const auto* p = e.params.find(param);
                if (!p) throw SceneError(e.loc, "mix needs a \"string " + param + "\" parameter");
                const std::string name = e.params.get_string(param, "");
                m.mix[k] = d.mix[k];
                if (d.mix[k] < 0)
                    warn(p->loc, "named material " + q(name) +
                                     " is not defined here; the default matte is used in the mix");
            }
        } else {
            // pbrt-v3 renders a material it does not know as matte, with a warning; so does
            // cmam with the ones it does not render (subsurface scattering, Fourier BSDFs, hair).
            m.type = Material::Type::Matte;
            m.kd = spectrum_input(e, s, "Kd", Rgb(0.5f));
            warn(e.loc, "material " + q(t) + " is rendered as \"matte\"" +
                            (e.params.find("Kd") ? " with its Kd" : "") +
                            " (cmam renders matte, mirror, glass, plastic, uber, metal, mix, and "
                            "substrate and translucent as plastic)");
            return m;  // its other parameters are not read: no warning for each
        }
        if (e.params.find("type")) e.params.get_string("type", "");
        if (e.params.find("bumpmap")) m.bump = float_input(e, s, "bumpmap", 0);
        e.params.check_unused("material " + q(t), m_warn, {});
        return m;
    }

    // --- shapes ---------------------------------------------------------------------------
    // Appends the shape's primitive (if it has any surface) to `out`.
    void shape(const pbrt::ShapeDesc& s, std::vector<std::unique_ptr<Primitive>>& out) {
        const Entity& e = s.entity;
        auto prim = std::make_unique<Primitive>();
        prim->material = s.material;
        finite_transform(s.world_from_object, e.loc, "shape");
        prim->flip = s.reverse_orientation ^ s.world_from_object.swaps_handedness();
        const std::vector<std::string> ignored = {"alpha", "shadowalpha"};
        if (e.type == "sphere" || e.type == "disk") {
            const Mat4 ow =
                inverse_or_error(s.world_from_object, e.loc, "the shape's transform is singular");
            prim->world_from_object = to34(s.world_from_object);
            prim->object_from_world = to34(ow);
            double r = finite_float(e, "radius", 1, true);
            prim->radius = r;
            double phimax = std::clamp(finite_float(e, "phimax", 360), 0.0, 360.0);
            prim->phi_max = phimax * std::numbers::pi / 180;
            if (e.type == "sphere") {
                prim->kind = Primitive::Kind::Sphere;
                double z0 = std::clamp(finite_float(e, "zmin", -r), -r, r);
                double z1 = std::clamp(finite_float(e, "zmax", r), -r, r);
                prim->zmin = std::min(z0, z1);
                prim->zmax = std::max(z0, z1);
                prim->theta_zmin = std::acos(std::clamp(prim->zmin / r, -1.0, 1.0));
                prim->theta_zmax = std::acos(std::clamp(prim->zmax / r, -1.0, 1.0));
                if (prim->theta_zmin == prim->theta_zmax)
                    throw SceneError(e.loc, "sphere has zmin == zmax");
            } else {
                prim->kind = Primitive::Kind::Disk;
                prim->height = finite_float(e, "height", 0);
                prim->inner_radius = finite_float(e, "innerradius", 0);
                if (prim->inner_radius < 0 || prim->inner_radius >= r)
                    throw SceneError(e.params.find("innerradius")->loc,
                                     "innerradius must be in [0, radius)");
            }
            e.params.check_unused("shape " + q(e.type), m_warn, ignored);
        } else if (e.type == "trianglemesh" || e.type == "plymesh" || e.type == "loopsubdiv" ||
                   is_tessellated_quadric(e.type)) {
            prim->kind = Primitive::Kind::Triangles;
            // pbrt-v3's cut-out masks (float textures or constants), read before the
            // parameters are checked.
            if (e.params.find("alpha")) prim->alpha = float_input(e, s.scope, "alpha", 1);
            if (e.params.find("shadowalpha"))
                prim->shadow_alpha = float_input(e, s.scope, "shadowalpha", 1);
            std::vector<float> P, N, UV;
            std::vector<int> idx;
            if (is_tessellated_quadric(e.type)) {
                QuadricMesh mesh = tessellate(e.type, quadric_params(e));
                P = std::move(mesh.positions);
                N = std::move(mesh.normals);
                UV = std::move(mesh.uvs);
                idx = std::move(mesh.indices);
                e.params.check_unused("shape " + q(e.type), m_warn, ignored);
            } else if (e.type == "plymesh") {
                const auto* fp = e.params.find("filename");
                if (!fp) throw SceneError(e.loc, "plymesh needs a \"string filename\" parameter");
                std::string path = pbrt::resolve_path(m_desc.base_dir, fp->loc,
                                                      e.params.get_string("filename", ""));
                // Each file is read once, however many shapes name it.
                auto& mesh = m_ply[path];
                if (!mesh) {
                    try {
                        mesh = std::make_unique<pbrt::PlyMesh>(pbrt::read_ply(path));
                    } catch (const pbrt::PlyError& err) {
                        throw SceneError(fp->loc, err.message());
                    }
                }
                P = mesh->positions;
                N = mesh->normals;
                UV = mesh->uvs;
                idx = mesh->indices;
                e.params.check_unused("shape \"plymesh\"", m_warn,
                                      {"alpha", "shadowalpha", "displacement", "edgelength"});
            } else {
                const std::string what = q(e.type);
                if (e.type == "loopsubdiv") {
                    // The control mesh stands for the limit surface (close for fine meshes).
                    warn(e.loc,
                         "shape \"loopsubdiv\" is rendered as its control mesh, not "
                         "subdivided");
                    (void)e.params.get_int("levels", 3);
                    (void)e.params.get_int("nlevels", 3);  // pbrt-v3 reads either name
                }
                auto p = e.params.get_point3s("P");
                if (!p) throw SceneError(e.loc, what + " needs a \"point3 P\" parameter");
                for (double x : finite_values(e, "P", *p)) P.push_back(float(x));
                std::size_t nv = P.size() / 3;
                if (auto i = e.params.get_ints("indices")) {
                    idx = *i;
                } else if (nv == 3) {
                    idx = {0, 1, 2};
                } else {
                    throw SceneError(e.loc, what + " needs an \"integer indices\" parameter");
                }
                if (idx.size() % 3 != 0)
                    throw SceneError(
                        e.params.find("indices")->loc,
                        "indices count " + std::to_string(idx.size()) + " is not a multiple of 3");
                for (int i : idx)
                    if (i < 0 || static_cast<std::size_t>(i) >= nv)
                        throw SceneError(e.params.find("indices")->loc,
                                         "index " + std::to_string(i) + " out of range (" +
                                             std::to_string(nv) + " vertices)");
                if (auto n = e.params.get_point3s("N")) {
                    if (n->size() != P.size())
                        throw SceneError(e.params.find("N")->loc,
                                         "N must have one normal per vertex of P");
                    for (double x : finite_values(e, "N", *n)) N.push_back(float(x));
                }
                const char* uvname = e.params.find("uv") ? "uv" : "st";
                if (auto uv = e.params.get_point2s(uvname)) {
                    if (uv->size() != 2 * nv)
                        throw SceneError(
                            e.params.find(uvname)->loc,
                            std::string(uvname) + " must have one (u,v) pair per vertex of P");
                    for (double x : finite_values(e, uvname, *uv)) UV.push_back(float(x));
                }
                e.params.check_unused("shape " + what, m_warn,
                                      {"alpha", "shadowalpha", "S", "faceIndices"});
            }
            std::size_t nv = P.size() / 3;
            prim->positions.resize(nv);
            for (std::size_t i = 0; i < nv; ++i) {
                auto w = s.world_from_object.apply_point({P[3 * i], P[3 * i + 1], P[3 * i + 2]});
                prim->positions[i] = Vec3(float(w[0]), float(w[1]), float(w[2]));
            }
            if (!N.empty()) {
                Mat4 inv_t;
                try {
                    inv_t = s.world_from_object.inverse().transposed();
                } catch (const SceneError&) {
                    throw SceneError(e.loc, "the shape's transform is singular");
                }
                prim->normals.resize(nv);
                for (std::size_t i = 0; i < nv; ++i) {
                    auto w = inv_t.apply_vector({N[3 * i], N[3 * i + 1], N[3 * i + 2]});
                    prim->normals[i] = Vec3(float(w[0]), float(w[1]), float(w[2]));
                }
            }
            if (!UV.empty()) {
                prim->uvs.resize(nv);
                for (std::size_t i = 0; i < nv; ++i) prim->uvs[i] = {UV[2 * i], UV[2 * i + 1]};
            }
            // Drop degenerate triangles (pbrt-v3 cannot hit them either).
            for (std::size_t t = 0; t + 2 < idx.size(); t += 3) {
                Vec3 a = prim->positions[idx[t]], b = prim->positions[idx[t + 1]],
                     c = prim->positions[idx[t + 2]];
                if (length(cross(b - a, c - a)) == 0) continue;
                prim->indices.insert(prim->indices.end(), {uint32_t(idx[t]), uint32_t(idx[t + 1]),
                                                           uint32_t(idx[t + 2])});
            }
            if (prim->indices.empty()) return;
        } else if (e.type == "curve") {
            warn(e.loc, "shape \"curve\" is not rendered (cmam has no curves); it is skipped");
            return;
        } else {
            throw SceneError(e.loc, "unsupported shape " + q(e.type) +
                                        " (supported: \"sphere\", \"disk\", \"cylinder\", "
                                        "\"cone\", \"paraboloid\", \"hyperboloid\", "
                                        "\"trianglemesh\", \"plymesh\", \"loopsubdiv\")");
        }
        prim->id = static_cast<uint32_t>(out.size());
        if (s.area_light >= 0 && &out == &m_scene->primitives) {
            // pbrt-v3 makes every shape in an AreaLightSource's scope emit; one light per shape
            // here, sampled uniformly by area over all its triangles.
            Light l = m_area_lights[static_cast<std::size_t>(s.area_light)];
            l.prim = static_cast<int>(prim->id);
            if (prim->kind == Primitive::Kind::Triangles) {
                prim->area_cdf.assign(1, 0.0);
                for (std::size_t t = 0; t < prim->indices.size(); t += 3) {
                    const Vec3 a = prim->positions[prim->indices[t]],
                               b = prim->positions[prim->indices[t + 1]],
                               c = prim->positions[prim->indices[t + 2]];
                    prim->area_cdf.push_back(prim->area_cdf.back() +
                                             0.5 * double(length(cross(b - a, c - a))));
                }
            }
            if (prim->kind == Primitive::Kind::Sphere) round_sphere(*prim);
            if (!l.intensity.is_black()) {
                prim->area_light = static_cast<int>(m_scene->lights.size());
                m_scene->lights.push_back(l);
            }
        }
        out.push_back(std::move(prim));
    }

    // Each object an instance uses is built once, in its own space; each instance places it
    // (algorithms.md §7.1). Textured-object ids (the CMAM's caches) are per instance.
    void instances() {
        std::vector<int> built(m_desc.objects.size(), -1);
        std::size_t next_id = m_scene->primitives.size();
        for (const pbrt::InstanceDesc& d : m_desc.instances) {
            int& o = built[d.object];
            if (o < 0) {
                o = static_cast<int>(m_scene->objects.size());
                m_scene->objects.emplace_back();
                for (const auto& s : m_desc.objects[d.object].shapes)
                    shape(s, m_scene->objects.back().primitives);
            }
            const std::size_t n = m_scene->objects[o].primitives.size();
            if (n == 0) continue;  // an empty object places nothing
            finite_transform(d.world_from_instance, d.loc, "object instance");
            const Mat4 inv = inverse_or_error(d.world_from_instance, d.loc,
                                              "the instance's transform is singular");
            Instance in;
            in.object = static_cast<uint32_t>(o);
            const auto w = to34(d.world_from_instance), iw = to34(inv);
            for (int k = 0; k < 12; ++k) {
                in.world_from_object[k] = static_cast<float>(w[k]);
                in.object_from_world[k] = static_cast<float>(iw[k]);
            }
            const double det = w[0] * (w[5] * w[10] - w[6] * w[9]) -
                               w[1] * (w[4] * w[10] - w[6] * w[8]) +
                               w[2] * (w[4] * w[9] - w[5] * w[8]);
            in.curvature_scale = static_cast<float>(std::cbrt(std::abs(det)));
            if (next_id + n > std::numeric_limits<uint32_t>::max())
                throw SceneError(d.loc, "more than 2^32 instanced primitives");
            in.first_id = static_cast<uint32_t>(next_id);
            next_id += n;
            m_scene->instances.push_back(in);
        }
    }

    QuadricParams quadric_params(const Entity& e) {
        QuadricParams p;
        if (e.type == "hyperboloid") {
            auto a = finite_values(e, "p1", e.params.get_point3("p1", {0, 0, 0}));
            auto b = finite_values(e, "p2", e.params.get_point3("p2", {1, 1, 1}));
            std::copy(a.begin(), a.end(), p.p1);
            std::copy(b.begin(), b.end(), p.p2);
            if (a[2] == b[2]) throw SceneError(e.loc, "hyperboloid p1 and p2 must differ in z");
        } else {
            p.radius = finite_float(e, "radius", 1, true);
        }
        if (e.type == "cone") p.height = finite_float(e, "height", 1, true);
        if (e.type == "cylinder" || e.type == "paraboloid") {
            p.zmin = finite_float(e, "zmin", e.type == "cylinder" ? -1 : 0);
            p.zmax = finite_float(e, "zmax", 1);
            if (p.zmin == p.zmax) throw SceneError(e.loc, e.type + " has zmin == zmax");
            if (e.type == "paraboloid" &&
                (std::min(p.zmin, p.zmax) < 0 || std::max(p.zmin, p.zmax) <= 0))
                throw SceneError(e.loc, "paraboloid zmin and zmax must be at least 0");
        }
        p.phimax = finite_float(e, "phimax", 360);
        return p;
    }

    // A whole sphere whose transform is a rotation, reflection or uniform scale plus a
    // translation stays a sphere: its centre and radius let area lights sample its cone.
    static void round_sphere(Primitive& prim) {
        if (prim.zmin > -prim.radius || prim.zmax < prim.radius ||
            prim.phi_max < 2 * std::numbers::pi)
            return;
        const auto& m = prim.world_from_object;
        double len2[3], dots[3];
        for (int c = 0; c < 3; ++c) {
            const int d = (c + 1) % 3;
            len2[c] = m[c] * m[c] + m[4 + c] * m[4 + c] + m[8 + c] * m[8 + c];
            dots[c] = m[c] * m[d] + m[4 + c] * m[4 + d] + m[8 + c] * m[8 + d];
        }
        for (int c = 0; c < 3; ++c)
            if (std::abs(len2[c] - len2[0]) > 1e-6 * len2[0] || std::abs(dots[c]) > 1e-6 * len2[0])
                return;
        prim.sphere_center = Vec3(float(m[3]), float(m[7]), float(m[11]));
        prim.sphere_radius = float(prim.radius * std::sqrt(len2[0]));
    }

    // pbrt-v3's "diffuse" area light: radiance L (times scale) leaving the surface.
    Light area_light(const Entity& e) {
        Light l;
        l.type = Light::Type::Area;
        if (e.type != "diffuse" && e.type != "area") {  // pbrt-v3 warns and goes on
            warn(e.loc, "unknown AreaLightSource " + q(e.type) +
                            " (pbrt-v3 has \"diffuse\", also named \"area\"): the shapes in "
                            "its scope do not emit");
            return l;  // black: no light is made
        }
        Rgb scale(1);
        if (auto sc = e.params.get_rgb("scale")) scale = to_rgb(finite_values(e, "scale", *sc));
        auto L = e.params.get_rgb("L");
        l.intensity = (L ? to_rgb(finite_values(e, "L", *L)) : Rgb(1)) * scale;
        l.two_sided = e.params.get_bool("twosided", false);
        l.samples = light_samples(e);
        e.params.check_unused("AreaLightSource \"diffuse\"", m_warn, {"nsamples", "samples"});
        return l;
    }

    // --- lights ---------------------------------------------------------------------------
    static Vec3 to_vec(const std::array<double, 3>& a) {
        return Vec3(float(a[0]), float(a[1]), float(a[2]));
    }
    static Rgb to_rgb(const pbrt::Rgb& c) { return Rgb(c[0], c[1], c[2]); }

    // pbrt-v3's infinite light image: a lat-long map in the light's frame, read as its imagemap
    // reads images (8-bit files decoded from sRGB); theta = 0 is the file's top row.
    // A light's "mapname" image, read as pbrt-v3 reads light images (8-bit files decoded from
    // sRGB).
    std::shared_ptr<const texture::FilteredTexture> light_image(const Entity& e,
                                                                const pbrt::Param& p) {
        const std::string path =
            pbrt::resolve_path(m_desc.base_dir, p.loc, e.params.get_string("mapname", ""));
        try {
            return std::make_shared<const texture::FilteredTexture>(
                load_texture(path, false, std::nullopt, 1.0f, texture::WrapMode::Repeat));
        } catch (const ImageIoError& err) {
            throw SceneError(p.loc, err.what());
        }
    }
    // The linear part of the light's transform's inverse (directions from world to light).
    static std::array<float, 9> light_from_world(const Entity& e, const Mat4& world_from_light) {
        const Mat4 inv =
            inverse_or_error(world_from_light, e.loc, "the light's transform is singular");
        std::array<float, 9> lw{};
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) lw[3 * i + j] = float(inv.m[i][j]);
        return lw;
    }

    std::shared_ptr<const EnvironmentMap> environment_map(const Entity& e, const pbrt::Param& p,
                                                          const Mat4& world_from_light) {
        auto env = std::make_shared<EnvironmentMap>(light_image(e, p),
                                                    light_from_world(e, world_from_light));
        if (m_opts.filter) env->set_filter({*m_opts.filter});
        return env;
    }

    void light(const pbrt::LightDesc& d) {
        const Entity& e = d.entity;
        Light l;
        Rgb scale(1);
        if (auto sc = e.params.get_rgb("scale")) scale = to_rgb(finite_values(e, "scale", *sc));
        const Mat4& m = d.world_from_light;
        finite_transform(m, e.loc, "light");
        auto intensity = [&](const char* name) {
            auto v = e.params.get_rgb(name);
            return (v ? to_rgb(finite_values(e, name, *v)) : Rgb(1)) * scale;
        };
        auto point = [&](const char* name, std::array<double, 3> def) {
            return finite_values(e, name, e.params.get_point3(name, def));
        };
        if (e.type == "point") {
            l.type = Light::Type::Point;
            l.intensity = intensity("I");
            l.position = to_vec(m.apply_point(point("from", {0, 0, 0})));
        } else if (e.type == "spot") {
            l.type = Light::Type::Spot;
            l.intensity = intensity("I");
            auto from = point("from", {0, 0, 0});
            auto to = point("to", {0, 0, 1});
            // pbrt-v3 names the falloff "conedeltaangle"; "conedelta" is read too (cmam read only
            // that name before).
            const char* delta_name = e.params.find("conedelta") && !e.params.find("conedeltaangle")
                                         ? "conedelta"
                                         : "conedeltaangle";
            double cone = finite_float(e, "coneangle", 30), delta = finite_float(e, delta_name, 5);
            l.position = to_vec(m.apply_point(from));
            Vec3 axis = to_vec(m.apply_vector({to[0] - from[0], to[1] - from[1], to[2] - from[2]}));
            if (length(axis) == 0)
                throw SceneError(e.loc, "spot light \"from\" and \"to\" coincide");
            l.direction = normalize(axis);
            l.cos_total = float(std::cos(cone * std::numbers::pi / 180));
            l.cos_falloff_start = float(std::cos((cone - delta) * std::numbers::pi / 180));
        } else if (e.type == "distant") {
            l.type = Light::Type::Distant;
            l.intensity = intensity("L");
            auto from = point("from", {0, 0, 0});
            auto to = point("to", {0, 0, 1});
            Vec3 w = to_vec(m.apply_vector({from[0] - to[0], from[1] - to[1], from[2] - to[2]}));
            if (length(w) == 0)
                throw SceneError(e.loc, "distant light \"from\" and \"to\" coincide");
            l.direction = normalize(w);
        } else if (e.type == "infinite") {
            l.type = Light::Type::Infinite;
            l.intensity = intensity("L");
            if (const auto* mp = e.params.find("mapname")) {
                l.env = environment_map(e, *mp, m);
                // Escaping rays filter the map over their ray differentials' footprint, with
                // the image textures' filter (EWA unless overridden); other footprint sources
                // point-sample it as pbrt-v3 does.
                l.env_footprint = !m_opts.lod || *m_opts.lod == FootprintMethod::Differentials;
                if (l.env_footprint) m_scene->needs_differentials = true;
            }
            e.params.get_int("samples",
                             1);  // pbrt-v3's sample count hint; one sample per lookup here
        } else if (e.type == "goniometric" || e.type == "projection") {
            // A point light at the light's origin whose intensity follows an image.
            l.type = e.type == "goniometric" ? Light::Type::Goniometric : Light::Type::Projection;
            l.intensity = intensity("I");
            l.position = to_vec(m.apply_point({0, 0, 0}));
            auto img = std::make_shared<LightImage>();
            img->kind = e.type == "goniometric" ? LightImage::Kind::Goniometric
                                                : LightImage::Kind::Projection;
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
        } else {
            throw SceneError(e.loc, "unsupported light " + q(e.type) +
                                        " (supported: \"point\", \"spot\", \"distant\", "
                                        "\"infinite\", \"goniometric\", \"projection\")");
        }
        // A delta light needs one shadow ray; the others take nsamples under directlighting.
        // (pbrt-v3's goniometric light has no fov, but scenes give it; pbrt-v3 warns too.)
        if (l.type == Light::Type::Infinite) l.samples = light_samples(e);
        e.params.check_unused("light " + q(e.type), m_warn, {"nsamples", "conedelta", "fov"});
        m_scene->lights.push_back(l);
    }
};

}  // namespace

void Camera::generate_ray(float px, float py, Vec3* org, Vec3* dir) const {
    const auto& m = world_from_camera;
    if (environment) {
        const float theta = kPi * py / yres, phi = 2 * kPi * px / xres;
        const Vec3 d(std::sin(theta) * std::cos(phi), std::cos(theta),
                     std::sin(theta) * std::sin(phi));
        *org = Vec3(m[3], m[7], m[11]);
        *dir = normalize(Vec3(m[0] * d.x + m[1] * d.y + m[2] * d.z,
                              m[4] * d.x + m[5] * d.y + m[6] * d.z,
                              m[8] * d.x + m[9] * d.y + m[10] * d.z));
        return;
    }
    float sx = screen[0] + (px / xres) * (screen[1] - screen[0]);
    float sy = screen[3] - (py / yres) * (screen[3] - screen[2]);
    if (orthographic) {
        *org = Vec3(m[0] * sx + m[1] * sy + m[3], m[4] * sx + m[5] * sy + m[7],
                    m[8] * sx + m[9] * sy + m[11]);
        *dir = normalize(Vec3(m[2], m[6], m[10]));
        return;
    }
    Vec3 d(sx * tan_half_fov, sy * tan_half_fov, 1);
    *org = Vec3(m[3], m[7], m[11]);
    *dir =
        normalize(Vec3(m[0] * d.x + m[1] * d.y + m[2] * d.z, m[4] * d.x + m[5] * d.y + m[6] * d.z,
                       m[8] * d.x + m[9] * d.y + m[10] * d.z));
}

std::size_t Scene::texture_memory_bytes() const {
    std::size_t n = 0;
    for (const auto& [k, img] : images) n += img->memory_bytes();
    return n;
}

std::unique_ptr<Scene> build_scene(const pbrt::SceneDesc& desc, const BuildOptions& options,
                                   const pbrt::WarningSink& warn) {
    return Builder(desc, options, warn).run();
}

}  // namespace cmam::render
