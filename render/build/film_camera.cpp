// render — scene building: film, camera (and the check of its rays), sampler, pixel filter
// and integrator settings.
#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>

#include "pbrt/parser.h"
#include "render/build/builder.h"
#include "render/error.h"
#include "render/lens.h"
#include "render/lighttrace.h"

namespace cmam::render::build_detail {

// Widest pinhole a realistic camera is rendered as, in degrees.
constexpr double kMaxRealisticFov = 170;

namespace {
// The side of the square count of samples nearest n (at least 1): what a sample count that is
// not a stratified grid's (pixelsamples, --spp, mutationsperpixel) is rendered as.
int square_side(long long n) {
    return std::max(1, static_cast<int>(std::lround(std::sqrt(double(n)))));
}
}  // namespace

void Builder::film() {
    const Entity& e = m_desc.film;
    FilmSettings& f = m_scene->film;
    if (e.given && e.type != "image")
        throw SceneError(e.loc,
                         "unsupported Film " + in_quotes(e.type) + " (supported: \"image\")");
    auto side = [&](const char* name, int def) {
        const int n = e.params.get_int(name, def);
        if (n < 1 || n > kMaxFilmSide)
            throw SceneError(loc_of(e, name), std::string(name) + " must be between 1 and " +
                                                  std::to_string(kMaxFilmSide) + ", got " +
                                                  std::to_string(n));
        return n;
    };
    f.xres = side("xresolution", kDefaultFilmWidth);
    f.yres = side("yresolution", kDefaultFilmHeight);
    const long long pixels = static_cast<long long>(f.xres) * f.yres;
    if (pixels > kMaxFilmPixels)
        throw SceneError(loc_of(e, "xresolution"),
                         "a film of " + std::to_string(f.xres) + "x" + std::to_string(f.yres) +
                             " = " + std::to_string(pixels) + " pixels is above cmam's limit of " +
                             std::to_string(kMaxFilmPixels));
    f.filename = e.params.get_string("filename", "pbrt.exr");
    double cw[4] = {0, 1, 0, 1};
    if (auto c = e.params.get_floats("cropwindow")) {
        if (c->size() != 4)
            throw SceneError(e.params.find("cropwindow")->loc, "cropwindow needs 4 values");
        for (int i = 0; i < 4; ++i) {
            if (!std::isfinite((*c)[i]))
                throw SceneError(
                    e.params.find("cropwindow")->loc,
                    "cropwindow values must be finite numbers, got " + pbrt::number_text((*c)[i]));
            cw[i] = std::clamp((*c)[i], 0.0, 1.0);
        }
    }
    // In single precision, as pbrt-v3 (200 x 0.6f is 120.0000076f, so its ceiling is 121).
    auto edge = [](int res, double c) {
        return static_cast<int>(std::ceil(static_cast<float>(res) * static_cast<float>(c)));
    };
    f.x0 = edge(f.xres, std::min(cw[0], cw[1]));
    f.x1 = edge(f.xres, std::max(cw[0], cw[1]));
    f.y0 = edge(f.yres, std::min(cw[2], cw[3]));
    f.y1 = edge(f.yres, std::max(cw[2], cw[3]));
    if (f.width() <= 0 || f.height() <= 0)
        throw SceneError(e.params.find("cropwindow")->loc, "cropwindow selects no pixels");
    // pbrt-v3 multiplies every pixel by "scale" (radiance only, not AOVs).
    f.scale = static_cast<float>(finite_float(e, "scale", 1));
    if (e.params.find("maxsampleluminance"))
        f.max_sample_luminance = static_cast<float>(finite_float(e, "maxsampleluminance", 1, true));
    // The film's physical size matters to pbrt-v3's realistic camera only.
    if (m_desc.camera.type == "realistic") m_film_diagonal = finite_float(e, "diagonal", 35, true);
    e.params.check_unused("Film \"image\"", m_warn, {"diagonal", "pixelbounds"});
}

void Builder::camera() {
    // No Camera directive: pbrt-v3's default camera, perspective with its default fov (90) and the
    // identity transform, at the origin looking along +z (a LookAt or other transform given
    // before WorldBegin without a Camera is dropped, as pbrt-v3 drops it).
    Entity e = m_desc.camera;
    if (!e.given) {
        e.type = "perspective";
        e.loc = m_desc.film.loc;
        warn(e.loc,
             "no Camera given: pbrt-v3's default, a perspective camera (fov 90) at the origin "
             "looking along +z");
    }
    if (e.type != "perspective" && e.type != "orthographic" && e.type != "environment" &&
        e.type != "realistic")
        throw SceneError(e.loc, "unsupported Camera " + in_quotes(e.type) +
                                    " (supported: \"perspective\", \"orthographic\", "
                                    "\"environment\", \"realistic\")");
    Camera& c = m_scene->camera;
    c.orthographic = e.type == "orthographic";
    c.environment = e.type == "environment";
    const bool realistic = e.type == "realistic";
    c.xres = m_scene->film.xres;
    c.yres = m_scene->film.yres;
    // A realistic camera's image is its whole film: it has no frame or screen window.
    double frame = double(c.xres) / c.yres;
    if (!realistic) frame = e.params.get_float("frameaspectratio", frame);
    if (!(frame > 0 && std::isfinite(frame)))
        throw SceneError(
            loc_of(e, "frameaspectratio"),
            "frameaspectratio must be a positive finite number, got " + pbrt::number_text(frame));
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
    if (auto sw = realistic ? std::nullopt : e.params.get_floats("screenwindow")) {
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
    if (realistic) {
        realistic_camera(e, c);
    } else {
        double fov = c.orthographic ? 90 : e.params.get_float("fov", 90);
        double halffov = c.orthographic ? -1 : e.params.get_float("halffov", -1);
        if (halffov > 0) fov = 2 * halffov;
        if (!(fov > 0 && fov < 180))
            throw SceneError(loc_of(e, "fov"), "fov must be in (0, 180) degrees");
        c.tan_half_fov = c.orthographic ? 1.0f : float(std::tan(fov * std::numbers::pi / 360));
        // pbrt-v3's thin lens, on the perspective camera (its orthographic camera's lens is left
        // out, with a warning; its environment camera has none).
        const double lens = finite_float(e, "lensradius", 0);
        const double focus = finite_float(e, "focaldistance", 1e6);
        if (lens < 0)
            throw SceneError(loc_of(e, "lensradius"),
                             "lensradius must be 0 or more, got " + pbrt::number_text(lens));
        if (lens > 0 && (c.orthographic || c.environment)) {
            warn(loc_of(e, "lensradius"),
                 "lensradius ignored: cmam renders the " + e.type + " camera without a lens");
        } else if (lens > 0) {
            if (!(focus > 0))
                throw SceneError(loc_of(e, "focaldistance"),
                                 "focaldistance must be positive, got " + pbrt::number_text(focus));
            c.lens_radius = float(lens);
            c.focal_distance = float(focus);
        }
    }
    const Mat4 wc =
        inverse_or_error(m_desc.camera_from_world, e.loc, "the camera transform is singular");
    auto m = to34(wc);
    for (int i = 0; i < 12; ++i) c.world_from_camera[i] = float(m[i]);
    check_camera_rays(c, e.loc);
    e.params.check_unused("Camera " + in_quotes(e.type), m_warn, {"shutteropen", "shutterclose"});
}

// pbrt-v3's realistic camera (algorithms.md §7.3): rays traced through the lens system of its
// "lensfile", focused at "focusdistance" with the aperture stop "aperturediameter" wide, from
// the film's physical extent (Film "diagonal"). Its paraxial field of view (§7.2) is kept for
// what ray cones spread by.
void Builder::realistic_camera(const Entity& e, Camera& c) {
    const pbrt::Param* file = e.params.find("lensfile");
    const std::string name = e.params.get_string("lensfile", "");
    if (name.empty())
        throw SceneError(file ? file->loc : e.loc,
                         "Camera \"realistic\" needs a \"string lensfile\" parameter");
    const std::string path = pbrt::resolve_path(m_desc.base_dir, file->loc, name);
    const double focus = finite_float(e, "focusdistance", 10, true);
    const double aperture = finite_float(e, "aperturediameter", 1, true);
    // Each step's RenderError becomes a SceneError at `loc`, its message after `prefix`.
    const auto at = [](const pbrt::FileLoc& loc, const std::string& prefix, auto step) {
        try {
            return step();
        } catch (const RenderError& err) {
            throw SceneError(loc, prefix + err.what());
        }
    };
    const auto interfaces = at(file->loc, "", [&] { return read_lens_file(path); });
    const std::string in_file = "lens file " + in_quotes(path) + ": ";
    const ParaxialLens lens = at(file->loc, in_file, [&] { return paraxial_lens(interfaces); });
    const double image =
        at(loc_of(e, "focusdistance"), in_file, [&] { return image_distance(lens, 1000 * focus); });
    const int shorter = std::min(c.xres, c.yres);
    const double half_side = m_film_diagonal / 2 * shorter / std::hypot(c.xres, c.yres);
    const double fov = 360 / std::numbers::pi * std::atan(half_side / image);
    c.tan_half_fov = float(std::tan(std::min(fov, kMaxRealisticFov) * std::numbers::pi / 360));
    RealisticLens::Settings rs;
    rs.interfaces = interfaces;
    rs.aperture_diameter = aperture;
    rs.focus_distance = focus;
    rs.film_diagonal = m_film_diagonal;
    rs.xres = c.xres;
    rs.yres = c.yres;
    rs.simple_weighting = e.params.get_bool("simpleweighting", true);
    c.realistic = at(loc_of(e, "focusdistance"), in_file,
                     [&] { return std::make_shared<const RealisticLens>(rs); });
    if (c.realistic->clamped_aperture() > 0)
        warn(loc_of(e, "aperturediameter"), "aperturediameter " + pbrt::number_text(aperture) +
                                                " mm is wider than the lens's aperture stop; its " +
                                                pbrt::number_text(c.realistic->clamped_aperture()) +
                                                " mm is used, as pbrt-v3 clamps it");
}

// Embree takes rays whose origin and direction are finite and within kMaxRayCoordinate.
// Camera rays are checked through the film's corners: the origin (orthographic) and the
// direction before normalisation are affine in the raster position, so the corners bound
// every other pixel's.
void Builder::check_camera_rays(const Camera& c, const pbrt::FileLoc& loc) {
    auto text = [](const Vec3& v) {
        return "(" + pbrt::number_text(v.x, 7) + ", " + pbrt::number_text(v.y, 7) + ", " +
               pbrt::number_text(v.z, 7) + ")";
    };
    // The image's corners, through the lens's centre and, with a lens, its rim's four extremes
    // (the concentric map's images of the square's edge midpoints).
    const float lens[5][2] = {{0.5f, 0.5f}, {0, 0.5f}, {1, 0.5f}, {0.5f, 0}, {0.5f, 1}};
    for (int corner = 0; corner < 4; ++corner)
        for (int k = 0; k < (c.has_lens() ? 5 : 1); ++k) {
            const float px = corner & 1 ? float(c.xres) : 0, py = corner & 2 ? float(c.yres) : 0;
            const CameraRay ray = c.generate_ray(px, py, lens[k][0], lens[k][1]);
            const Vec3 &org = ray.org, &dir = ray.dir;
            const std::string at = " at raster position (" + pbrt::number_text(px) + ", " +
                                   pbrt::number_text(py) + ")";
            for (float x : {org.x, org.y, org.z})
                if (!(std::abs(x) <= kMaxRayCoordinate))
                    throw SceneError(
                        loc, "camera rays start at " + text(org) + at +
                                 (k > 0 ? " and the lens's rim" : "") +
                                 ", beyond cmam's limit of " +
                                 pbrt::number_text(kMaxRayCoordinate, 7) +
                                 " on coordinates (check the camera transform" +
                                 (k > 0 ? ", screenwindow and lensradius)" : " and screenwindow)"));
            if (!(std::abs(length(dir) - 1) < 1e-3f))
                throw SceneError(loc, "camera rays have direction " + text(dir) + at +
                                          (k > 0 ? " and the lens's rim" : "") +
                                          ", not a finite unit vector (check the camera "
                                          "transform, screenwindow and " +
                                          (c.has_lens() ? "focaldistance)" : "frameaspectratio)"));
        }
}

void Builder::sampler() {
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
        // pbrt-v3's defaults: 4 samples per pixel for random, 16 for the others.
        int n = e.params.get_int("pixelsamples", e.type == "random" ? 4 : 16);
        if (n <= 0) throw SceneError(e.loc, "pixelsamples must be positive");
        if (n > kMaxSamplesPerPixel)
            throw SceneError(loc_of(e, "pixelsamples"),
                             "pixelsamples " + std::to_string(n) + " is above cmam's limit of " +
                                 std::to_string(kMaxSamplesPerPixel) + " samples per pixel");
        // Sobol, (0,2)-sequence and maxmindist samplers take a power of two, rounding up as
        // pbrt-v3 does (with its warning); the grid below comes from that count.
        if (e.type != "halton" && e.type != "random" && !std::has_single_bit(unsigned(n))) {
            const int up = static_cast<int>(std::bit_ceil(unsigned(n)));
            warn(loc_of(e, "pixelsamples"),
                 "pixelsamples " + std::to_string(n) + " rounded up to a power of two, " +
                     std::to_string(up) + ", as pbrt-v3's " + in_quotes(e.type) + " sampler does");
            n = up;
        }
        int k = square_side(n);
        s.xsamples = s.ysamples = k;
        // With --spp the count comes from there (set below), not from pixelsamples; under mlt
        // from its mutationsperpixel (mlt_samples).
        const bool mlt = m_desc.integrator.given && m_desc.integrator.type == "mlt";
        const std::string count =
            m_opts.spp_override > 0 ? std::string(", as many as --spp asks for")
            : mlt ? std::string(", as many as the mlt integrator's mutationsperpixel")
                  : " with " + std::to_string(k) + "x" + std::to_string(k) + " per pixel";
        warn(e.loc, "Sampler " + in_quotes(e.type) +
                        " is rendered as \"stratified\" jittered samples" + count);
        e.params.check_unused("Sampler " + in_quotes(e.type), m_warn, names_of(e));
    } else {
        throw SceneError(e.loc, "unknown Sampler " + in_quotes(e.type));
    }
    if (m_opts.spp_override > kMaxSamplesPerPixel)
        throw SceneError("--spp " + std::to_string(m_opts.spp_override) +
                         " is above cmam's limit of " + std::to_string(kMaxSamplesPerPixel));
    if (m_opts.spp_override > 0) {
        const int k = square_side(m_opts.spp_override);
        s.xsamples = s.ysamples = k;
        s.jitter = k > 1;
    }
    check_samples_per_row(m_opts.spp_override > 0 ? pbrt::FileLoc{} : e.loc);
}

// A row of the film holds every sample of its pixels at once (and sample numbers along a row or
// column are ints), so the samples along the film's larger side are bounded too.
void Builder::check_samples_per_row(const pbrt::FileLoc& loc) const {
    const FilmSettings& f = m_scene->film;
    const long long spp = m_scene->sampler.spp();
    const long long side = std::max(f.xres, f.yres), per_row = side * spp;
    if (per_row > kMaxSamplesPerRow)
        throw SceneError(
            loc, std::to_string(spp) + " samples per pixel along " + std::to_string(side) +
                     " pixels (the film's larger side) = " + std::to_string(per_row) +
                     " samples, above cmam's limit of " + std::to_string(kMaxSamplesPerRow));
}

void Builder::filter() {
    const Entity& e = m_desc.filter;
    if (!e.given) return;
    using K = PixelFilter::Kind;
    PixelFilter f;
    double radius = 2;  // pbrt-v3's default radius for all but the box and sinc
    if (e.type == "box") {
        f.kind = K::Box;
        radius = 0.5;
    } else if (e.type == "gaussian") {
        f.kind = K::Gaussian;
        f.alpha = static_cast<float>(finite_float(e, "alpha", 2, true));
    } else if (e.type == "mitchell") {
        f.kind = K::Mitchell;
        f.b = static_cast<float>(finite_float(e, "B", 1.0 / 3));
        f.c = static_cast<float>(finite_float(e, "C", 1.0 / 3));
    } else if (e.type == "sinc") {
        f.kind = K::Sinc;
        radius = 4;
        f.tau = static_cast<float>(finite_float(e, "tau", 3, true));
    } else if (e.type == "triangle") {
        f.kind = K::Triangle;
    } else {
        throw SceneError(e.loc, "unknown PixelFilter " + in_quotes(e.type));
    }
    // A sample counts for every pixel within the radius: beyond kMaxFilterRadius pixels a side
    // (a blur wider than any reconstruction filter) the radius is bounded, with a warning.
    auto width = [&](const char* name) {
        double r = finite_float(e, name, radius, true);
        if (r > kMaxFilterRadius) {
            warn(loc_of(e, name), std::string("PixelFilter ") + name + " " + pbrt::number_text(r) +
                                      " is rendered as " + pbrt::number_text(kMaxFilterRadius) +
                                      " pixels");
            r = kMaxFilterRadius;
        }
        return static_cast<float>(r);
    };
    f.rx = width("xwidth");
    f.ry = width("ywidth");
    f.tabulate();
    m_scene->film.filter = f;
    e.params.check_unused("PixelFilter " + in_quotes(e.type), m_warn);
}

void Builder::integrator() {
    const Entity& e = m_desc.integrator;
    if (!e.given) {
        m_scene->path_tracing = true;  // pbrt-v3's default integrator: "path"
        return;
    }
    // pbrt-v3's directlighting is whitted's recursion with every light sampled nsamples
    // times ("all", its default) or one light chosen per point ("one": here each light
    // once, the same expectation).
    const bool direct = e.type == "directlighting";
    // pbrt-v3's path integrator, and volpath, which adds participating media (media()); its
    // bdpt and mlt compute the same light transport with media: they are path traced too, with
    // the light paths a path tracer cannot do without (lighttrace.h) where the camera allows.
    const bool path =
        e.type == "path" || e.type == "volpath" || e.type == "bdpt" || e.type == "mlt";
    if (path) {
        m_scene->path_tracing = true;
        m_scene->rr_threshold = static_cast<float>(finite_float(e, "rrthreshold", 1));
        if (e.type == "mlt") mlt_samples(e);
        if (e.type != "path" && e.type != "volpath") {
            m_scene->light_tracing = light_tracing_camera(m_scene->camera);
            warn(e.loc,
                 "Integrator " + in_quotes(e.type) + " is rendered as \"volpath\" (" +
                     (m_scene->light_tracing
                          ? "a path tracer, with light paths from point, spot and distant lights "
                            "joined to the camera for their caustics through mirrors and glass; "
                            "the same light transport but for those caustics lit again and seen "
                            "through mirrors or glass"
                          : "a path tracer, which misses the caustics of point, spot and distant "
                            "lights through mirrors and glass: \"sppm\" renders those; light "
                            "paths join only a perspective camera whose transform neither scales "
                            "nor shears") +
                     ")");
        }
    } else if (e.type == "sppm") {
        sppm_integrator(e);
    } else if (direct) {
        const std::string strategy = e.params.get_string("strategy", "all");
        if (strategy != "all" && strategy != "one")
            warn(e.params.find("strategy")->loc,
                 "unknown direct lighting strategy " + in_quotes(strategy) +
                     " (expected \"all\" or \"one\"); \"all\" is used, as pbrt-v3 does");
        m_light_samples = strategy != "one";
    } else if (e.type == "ambientocclusion") {
        // pbrt-v3's: "nsamples" directions at each camera ray's first hit (0 renders black, as
        // in pbrt-v3), "cossample" cosine-weighted or uniform.
        m_scene->ambient_occlusion = true;
        const int n = e.params.get_int("nsamples", 64);
        if (n < 0)
            throw SceneError(loc_of(e, "nsamples"),
                             "nsamples must not be negative, got " + std::to_string(n));
        if (n == 0)
            warn(loc_of(e, "nsamples"),
                 "nsamples 0: no direction is sampled and the image is black, as in pbrt-v3");
        constexpr int kMaxAoSamples = 1 << 16;
        if (n > kMaxAoSamples)
            warn(loc_of(e, "nsamples"),
                 "nsamples " + std::to_string(n) + " is above cmam's limit of " +
                     std::to_string(kMaxAoSamples) + ", which is used instead");
        m_scene->ao_samples = std::min(n, kMaxAoSamples);
        m_scene->ao_cosine = e.params.get_bool("cossample", true);
    } else if (e.type != "whitted")
        warn(e.loc, "Integrator " + in_quotes(e.type) + " is rendered as \"whitted\"");
    if (const auto* p = !m_scene->ambient_occlusion ? e.params.find("maxdepth") : nullptr) {
        const int depth = e.params.get_int("maxdepth", 5);
        m_scene->max_depth = std::min(depth, kMaxDepthLimit);
        if (depth > kMaxDepthLimit)
            warn(p->loc, "maxdepth " + std::to_string(depth) + " is above cmam's limit of " +
                             std::to_string(kMaxDepthLimit) + ", which is used instead");
    }
    e.params.check_unused("Integrator " + in_quotes(e.type), m_warn,
                          e.type == "whitted" || direct || e.type == "path" ||
                                  e.type == "volpath" || e.type == "ambientocclusion" ||
                                  e.type == "sppm"
                              ? std::vector<std::string>{"pixelbounds", "lightsamplestrategy"}
                              : names_of(e));
}

// pbrt-v3's mlt takes no Sampler: its image has `mutationsperpixel` samples per pixel (default
// 100), here the path tracer's, rounded to a square as the samplers' counts are; --spp wins.
// Its Metropolis parameters (bootstrapsamples, chains, largestepprobability, sigma) change the
// noise only, and are reported unused.
void Builder::mlt_samples(const Entity& e) {
    const int n = e.params.get_int("mutationsperpixel", 100);
    if (n < 1)
        throw SceneError(loc_of(e, "mutationsperpixel"),
                         "mutationsperpixel must be at least 1, got " + std::to_string(n));
    if (n > kMaxSamplesPerPixel)
        throw SceneError(loc_of(e, "mutationsperpixel"),
                         "mutationsperpixel " + std::to_string(n) + " is above cmam's limit of " +
                             std::to_string(kMaxSamplesPerPixel) + " samples per pixel");
    if (m_opts.spp_override > 0) return;
    m_scene->sampler.xsamples = m_scene->sampler.ysamples = square_side(n);
    m_scene->sampler.jitter = true;
    check_samples_per_row(loc_of(e, "mutationsperpixel"));
}

// pbrt-v3's "sppm" (Scene::sppm): its parameters, those it would fail on an error here (no
// iteration: pbrt-v3 writes no image; no radius: a black or NaN one).
void Builder::sppm_integrator(const Entity& e) {
    m_scene->sppm.on = true;
    m_scene->path_tracing = true;  // (an AOV render's paths, and MIS in the direct light)
    // "iterations" is pbrt-v3's other name for numiterations, and wins where both are given
    // (both are read, as pbrt-v3 reads both).
    const char* iterations_name = e.params.find("iterations") ? "iterations" : "numiterations";
    const int iterations = e.params.get_int("iterations", e.params.get_int("numiterations", 64));
    if (iterations < 1)
        throw SceneError(loc_of(e, iterations_name), std::string(iterations_name) +
                                                         " must be at least 1, got " +
                                                         std::to_string(iterations));
    m_scene->sppm.iterations = iterations;
    // --spp sets the iterations (each a camera sample per pixel), rounded as for the samplers.
    if (m_opts.spp_override > 0) {
        const int k = square_side(m_opts.spp_override);
        m_scene->sppm.iterations = k * k;
    }
    // (0 or negative: one photon per pixel of the cropped film, as in pbrt-v3.)
    const int photons = e.params.get_int("photonsperiteration", -1);
    m_scene->sppm.photons = photons > 0 ? photons : 0;
    const double radius = finite_float(e, "radius", 1);
    if (!(radius > 0))
        throw SceneError(loc_of(e, "radius"),
                         "radius must be positive, got " + pbrt::number_text(radius));
    m_scene->sppm.radius = static_cast<float>(radius);
    // Only the progress images pbrt-v3 writes depend on it: the final image is the same.
    (void)e.params.get_int("imagewritefrequency", 0);
}

}  // namespace cmam::render::build_detail
