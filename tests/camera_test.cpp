// Camera rays follow pbrt-v3's perspective camera: fov spans the shorter axis, raster y down.
// Its realistic camera is that pinhole, of the fov its lens system gives.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "expect_throw.h"
#include "render/integrator.h"
#include "render/lens.h"
#include "render/tracer.h"
#include "scene_util.h"
#include "temp_dir.h"

using namespace cmam;
using render::Vec3;

namespace {
constexpr double kDeg = 3.14159265358979323846 / 180;
void expect_dir(const Vec3& d, Vec3 e, float eps = 1e-6f) {
    e = render::normalize(e);
    EXPECT_NEAR(d.x, e.x, eps);
    EXPECT_NEAR(d.y, e.y, eps);
    EXPECT_NEAR(d.z, e.z, eps);
}
}  // namespace

TEST(Camera, CentreAndEdgesOfASquareImage) {
    auto s = test::scene_from(
        "LookAt 0 0 0  0 0 1  0 1 0 Camera \"perspective\" \"float fov\" 90 "
        "Film \"image\" \"integer xresolution\" 100 \"integer yresolution\" 100 WorldBegin "
        "WorldEnd");
    Vec3 d = s->camera.generate_ray(50, 50).dir;
    expect_dir(d, Vec3(0, 0, 1));
    d = s->camera.generate_ray(0, 50).dir;  // left edge: 45 degrees to the left (-x)
    expect_dir(d, Vec3(-1, 0, 1));
    d = s->camera.generate_ray(50, 0).dir;  // top row looks up
    expect_dir(d, Vec3(0, 1, 1));
}

// A scene without a Film, or with a Film that gives no resolution, is 1280x720 as in pbrt-v3
// (its CreateFilm; pbrt-v2 had 640x480), so its camera frames the 16:9 view pbrt-v3 renders.
TEST(Camera, TheDefaultFilmIsPbrtV3s) {
    for (const char* film : {"", "Film \"image\" \"string filename\" \"x.exr\" "}) {
        auto s = test::scene_from(std::string(film) +
                                  "Camera \"perspective\" \"float fov\" 60 WorldBegin WorldEnd");
        EXPECT_EQ(s->film.width(), 1280);
        EXPECT_EQ(s->film.height(), 720);
        // The fov spans the shorter axis, the height: the right edge is 16/9 times as far out.
        const float t = float(std::tan(30 * kDeg));
        expect_dir(s->camera.generate_ray(640, 0).dir, Vec3(0, t, 1));
        expect_dir(s->camera.generate_ray(1280, 360).dir, Vec3(16.0f / 9 * t, 0, 1));
    }
    auto s = test::scene_from(
        "Film \"image\" \"integer xresolution\" 300 Camera \"perspective\" WorldBegin WorldEnd");
    EXPECT_EQ(s->film.width(), 300);
    EXPECT_EQ(s->film.height(), 720);
}

// A scene without a Camera directive renders, with a warning, through pbrt-v3's default camera:
// perspective, fov 90, at the origin looking along +z; a LookAt given without a Camera is dropped
// with the other transforms at WorldBegin, as in pbrt-v3.
TEST(Camera, TheDefaultCameraIsPbrtV3s) {
    for (const char* before : {"", "LookAt 0 0 5  0 0 0  0 1 0 "}) {
        SCOPED_TRACE(before);
        std::vector<std::string> warnings;
        auto s = render::build_scene(
            pbrt::parse_string(std::string(before) +
                                   "Film \"image\" \"integer xresolution\" 100 "
                                   "\"integer yresolution\" 100 WorldBegin WorldEnd",
                               "t.pbrt"),
            {}, [&](const std::string& w) { warnings.push_back(w); });
        const render::CameraRay centre = s->camera.generate_ray(50, 50);
        EXPECT_NEAR(centre.org.x, 0, 1e-6);
        EXPECT_NEAR(centre.org.z, 0, 1e-6);
        expect_dir(centre.dir, Vec3(0, 0, 1));
        expect_dir(s->camera.generate_ray(50, 0).dir, Vec3(0, 1, 1));  // fov 90: 45 degrees up
        EXPECT_EQ(std::count(warnings.begin(), warnings.end(),
                             "t.pbrt:1:" + std::string(*before ? "28" : "1") +
                                 ": warning: no Camera given: pbrt-v3's default, a perspective "
                                 "camera (fov 90) at the origin looking along +z"),
                  1);
    }
}

TEST(Camera, FovSpansTheShorterAxis) {
    for (auto [xr, yr] : {std::pair{200, 100}, std::pair{100, 200}}) {
        auto s = test::scene_from(
            "Camera \"perspective\" \"float fov\" 60 Film \"image\" \"integer xresolution\" " +
            std::to_string(xr) + " \"integer yresolution\" " + std::to_string(yr) +
            " WorldBegin WorldEnd");
        Vec3 d;
        float t = float(std::tan(30 * kDeg));
        if (xr > yr) {
            d = s->camera.generate_ray(float(xr) / 2, 0).dir;
            expect_dir(d, Vec3(0, t, 1));
            d = s->camera.generate_ray(float(xr), float(yr) / 2).dir;
            expect_dir(d, Vec3(2 * t, 0, 1));
        } else {
            d = s->camera.generate_ray(0, float(yr) / 2).dir;
            expect_dir(d, Vec3(-t, 0, 1));
            d = s->camera.generate_ray(float(xr) / 2, 0).dir;
            expect_dir(d, Vec3(0, 2 * t, 1));
        }
    }
}

TEST(Camera, LookAtPlacesTheCamera) {
    auto s = test::scene_from(
        "LookAt 1 2 3  1 2 -7  0 1 0 Camera \"perspective\" Film \"image\" \"integer xresolution\" "
        "10 "
        "\"integer yresolution\" 10 WorldBegin WorldEnd");
    const render::CameraRay ray = s->camera.generate_ray(5, 5);
    const render::Vec3& o = ray.org;
    render::Vec3 d = ray.dir;
    EXPECT_NEAR(o.x, 1, 1e-6);
    EXPECT_NEAR(o.y, 2, 1e-6);
    EXPECT_NEAR(o.z, 3, 1e-6);
    expect_dir(d, Vec3(0, 0, -1));
    d = s->camera.generate_ray(0, 5).dir;  // looking down -z with +y up: screen left is world +x
    EXPECT_GT(d.x, 0.5f);
}

// The environment camera's ray and its neighbours one pixel right and down, made together with
// shared sines and cosines, are generate_ray's bit for bit (the render's ray differentials are
// their differences), at the poles, the seam and in between, under a turned camera.
TEST(Camera, EnvironmentDirectionsAreGenerateRaysBitForBit) {
    auto s = test::scene_from(
        "LookAt 0.3 -1 2  4 2 -1  0.2 0 1 Camera \"environment\" Film \"image\" "
        "\"integer xresolution\" 400 \"integer yresolution\" 200 WorldBegin WorldEnd");
    ASSERT_TRUE(s->camera.environment);
    auto same = [](const Vec3& a, const Vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; };
    int checked = 0;
    for (float py : {0.0f, 0.37f, 17.25f, 99.5f, 150.125f, 199.0f, 199.99f})
        for (float px : {0.0f, 0.5f, 123.375f, 250.0f, 398.75f, 399.0f, 399.9f}) {
            Vec3 dirs[3];
            s->camera.environment_directions(px, py, dirs);
            EXPECT_TRUE(same(dirs[0], s->camera.generate_ray(px, py).dir)) << px << " " << py;
            EXPECT_TRUE(same(dirs[1], s->camera.generate_ray(px + 1, py).dir)) << px << " " << py;
            EXPECT_TRUE(same(dirs[2], s->camera.generate_ray(px, py + 1).dir)) << px << " " << py;
            ++checked;
        }
    EXPECT_EQ(checked, 49);
}

TEST(Camera, ScreenWindowAndCrop) {
    auto s = test::scene_from(
        "Camera \"perspective\" \"float fov\" 90 \"float screenwindow\" [0 1 0 1] "
        "Film \"image\" \"integer xresolution\" 10 \"integer yresolution\" 10 \"float cropwindow\" "
        "[0.5 1 0 0.25] "
        "WorldBegin WorldEnd");
    Vec3 d = s->camera.generate_ray(0, 10).dir;  // bottom-left of the window is screen (0,0)
    expect_dir(d, Vec3(0, 0, 1));
    EXPECT_EQ(s->film.x0, 5);
    EXPECT_EQ(s->film.x1, 10);
    EXPECT_EQ(s->film.y0, 0);
    EXPECT_EQ(s->film.y1, 3);
}

// pbrt-v3's realistic camera (algorithms.md §7.2, §7.3): its lens system's paraxial optics, and
// rays traced through it. The lenses are written to lens files in a temporary folder.
namespace {

// A single glass element: front radius r1, back radius r2, thickness d and index n (mm), its
// back 50 mm from the film (a distance focusing replaces).
std::string element(double r1, double r2, double d, double n) {
    return "# radius thickness eta aperture\n" + std::to_string(r1) + " " + std::to_string(d) +
           " " + std::to_string(n) + " 20\n" + std::to_string(r2) + " 50 0 20\n";
}

struct LensScene {
    test::TempDir dir{"cmam_lens_test"};
    std::string scene = (dir.path / "scene.pbrt").string();

    void write(const std::string& name, const std::string& text) const {
        std::ofstream(dir.path / name) << text;
    }
    // The pbrt text of a realistic camera with `params` before a film of `film` parameters.
    static std::string text(const std::string& params, const std::string& film) {
        return "Camera \"realistic\" " + params + "\nFilm \"image\" " + film +
               "\nWorldBegin WorldEnd\n";
    }
    std::unique_ptr<render::Scene> build(const std::string& params, const std::string& film,
                                         std::vector<std::string>* warnings = nullptr) const {
        auto sink = [&](const std::string& w) {
            if (warnings) warnings->push_back(w);
        };
        return render::build_scene(pbrt::parse_string(text(params, film), scene), {}, sink);
    }
};

// A 400x300 film 100 mm across its diagonal is 80 mm x 60 mm: 30 mm from its centre to its top
// and bottom edges.
const std::string kFilm100 =
    "\"integer xresolution\" 400 \"integer yresolution\" 300 \"float diagonal\" 100";

}  // namespace

// pbrt-v3's thin lens ("lensradius", "focaldistance"): a ray leaves a point of the lens disc
// (the concentric map of its sample) towards where the pinhole ray through the same raster
// position meets the plane of focus; the lens's centre gives the pinhole ray.
TEST(Camera, ThinLensRaysMeetThePinholesOnThePlaneOfFocus) {
    auto s = test::scene_from(
        "LookAt 1 2 3  1 2 10  0 1 0 Camera \"perspective\" \"float fov\" 50 \"float lensradius\" "
        "0.5 \"float focaldistance\" 4 Film \"image\" \"integer xresolution\" 64 "
        "\"integer yresolution\" 48 WorldBegin WorldEnd");
    const render::Camera& c = s->camera;
    ASSERT_TRUE(c.has_lens());
    const Vec3 eye(1, 2, 3);
    uint64_t state = 12345;
    auto next = [&] {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return float(state >> 40) * 0x1.0p-24f;
    };
    float farthest = 0;
    for (int k = 0; k < 200; ++k) {
        const float px = 64 * next(), py = 48 * next(), lu = next(), lv = next();
        const render::CameraRay pin = c.generate_ray(px, py), lens = c.generate_ray(px, py, lu, lv);
        const Vec3 o = lens.org - eye;
        EXPECT_NEAR(o.z, 0, 1e-6f);  // on the lens, in the plane z = 3 facing +z
        EXPECT_LE(std::hypot(o.x, o.y), 0.5f + 1e-6f);
        farthest = std::max(farthest, std::hypot(o.x, o.y));
        EXPECT_NEAR(render::length(lens.dir), 1, 1e-6f);
        // Both reach the plane of focus z = 3 + 4 at the same point.
        const Vec3 a = pin.org + pin.dir * (4 / pin.dir.z),
                   b = lens.org + lens.dir * (4 / lens.dir.z);
        EXPECT_NEAR(render::length(a - b), 0, 2e-5f) << px << " " << py;
    }
    EXPECT_GT(farthest, 0.45f);  // the samples cover the disc
    const render::CameraRay centre = c.generate_ray(20, 30, 0.5f, 0.5f);
    EXPECT_EQ(centre.org.x, eye.x);
    expect_dir(centre.dir, c.generate_ray(20, 30).dir);
    // Without a lens, and for the orthographic camera (with a warning), the pinhole's rays.
    auto pinhole = test::scene_from("Camera \"perspective\" WorldBegin WorldEnd");
    EXPECT_FALSE(pinhole->camera.has_lens());
    const render::CameraRay p1 = pinhole->camera.generate_ray(3, 4, 0.9f, 0.1f),
                            p2 = pinhole->camera.generate_ray(3, 4);
    EXPECT_EQ(p1.dir.x, p2.dir.x);
    EXPECT_EQ(p1.org.y, p2.org.y);
    std::vector<std::string> warnings;
    render::build_scene(
        pbrt::parse_string("Camera \"orthographic\" \"float lensradius\" 0.1 WorldBegin WorldEnd",
                           "t.pbrt"),
        {}, [&](const std::string& w) { warnings.push_back(w); });
    ASSERT_FALSE(warnings.empty());
    EXPECT_EQ(warnings.back(),
              "t.pbrt:1:23: warning: lensradius ignored: cmam renders the orthographic camera "
              "without a lens");
    EXPECT_THROW_MSG(
        test::scene_from("Camera \"perspective\" \"float lensradius\" -1 WorldBegin WorldEnd"),
        pbrt::SceneError, "t.pbrt:1:22: error: lensradius must be 0 or more, got -1");
    EXPECT_THROW_MSG(test::scene_from("Camera \"perspective\" \"float lensradius\" 1 "
                                      "\"float focaldistance\" 0 WorldBegin WorldEnd"),
                     pbrt::SceneError, "t.pbrt:1:43: error: focaldistance must be positive, got 0");
    // A lens whose rim starts rays beyond Embree's coordinates, or a plane of focus so near that
    // the directions overflow: located errors, not a render (Embree asserted on such rays).
    EXPECT_THROW_MSG(
        test::scene_from("Camera \"perspective\" \"float lensradius\" 1e30 WorldBegin WorldEnd"),
        pbrt::SceneError,
        "t.pbrt:1:1: error: camera rays start at (-1e+30, 0, 0) at raster position (0, 0) and "
        "the lens's rim, beyond cmam's limit of 1e+18 on coordinates (check the camera "
        "transform, screenwindow and lensradius)");
    EXPECT_THROW_MSG(test::scene_from("Camera \"perspective\" \"float lensradius\" 1 "
                                      "\"float focaldistance\" 1e-36 WorldBegin WorldEnd"),
                     pbrt::SceneError,
                     "t.pbrt:1:1: error: camera rays have direction (0, 0, 0) at raster position "
                     "(0, 0) and the lens's rim, not a finite unit vector (check the camera "
                     "transform, screenwindow and focaldistance)");
}

// A pixel's lens samples are stratified as its image-plane samples are: its n = nx x ny samples
// take the n strata of the lens square once each, in an order that changes from pixel to pixel.
TEST(Camera, LensSamplesTakeEachStratumOncePerPixel) {
    for (auto [nx, ny] : {std::pair{4, 3}, std::pair{1, 1}, std::pair{8, 8}, std::pair{3, 5}}) {
        std::vector<std::vector<int>> orders;
        for (uint64_t pixel = 1; pixel <= 20; ++pixel) {
            std::vector<int> stratum_of(std::size_t(nx * ny));
            std::vector<bool> taken(std::size_t(nx * ny), false);
            for (int sample = 0; sample < nx * ny; ++sample) {
                float lu, lv;
                render::lens_sample(pixel * 7919, sample, nx, ny, lu, lv);
                ASSERT_TRUE(lu >= 0 && lu < 1 && lv >= 0 && lv < 1) << lu << " " << lv;
                const int cell = int(lv * float(ny)) * nx + int(lu * float(nx));
                EXPECT_FALSE(taken[std::size_t(cell)]) << nx << "x" << ny << " " << sample;
                taken[std::size_t(cell)] = true;
                stratum_of[std::size_t(sample)] = cell;
            }
            orders.push_back(stratum_of);
        }
        if (nx * ny > 1) {
            EXPECT_GT(std::count_if(orders.begin(), orders.end(),
                                    [&](const std::vector<int>& o) { return o != orders[0]; }),
                      10);
        }
    }
}

// What lies on the plane of focus stays sharp and what lies off it blurs: the edge of a white
// square seen against black, rendered through the lens at its distance and at twice it.
TEST(Camera, ThinLensBlursOnlyWhatIsOffThePlaneOfFocus) {
    // The edge x = 0 of a white half-plane at distance 5, seen through a lens of radius 0.2: in
    // focus, one pixel at most straddles it; focused at 10, its circle of confusion spans
    // 0.4 (1/5 - 1/10) = 0.04 radians, about 4.9 pixels of 0.0082.
    auto blurred_pixels = [](float focus) {
        auto s = test::scene_from(
            "LookAt 0 0 0  0 0 1  0 1 0 Camera \"perspective\" \"float fov\" 30 "
            "\"float lensradius\" 0.2 \"float focaldistance\" " +
            std::to_string(focus) +
            " Film \"image\" \"integer xresolution\" 64 \"integer yresolution\" 64 "
            "\"float cropwindow\" [0 1 0.45 0.55] "
            "Sampler \"stratified\" \"integer xsamples\" 8 \"integer ysamples\" 8 "
            "Integrator \"whitted\" WorldBegin AttributeBegin AreaLightSource \"diffuse\" "
            "\"rgb L\" [1 1 1] \"bool twosided\" true Shape \"trianglemesh\" "
            "\"point3 P\" [-100 -100 5  0 -100 5  0 100 5  -100 100 5] "
            "\"integer indices\" [0 1 2 0 2 3] AttributeEnd WorldEnd");
        const render::Framebuffer fb = render::render(*s, {}, nullptr);
        int grey = 0;  // pixels of the middle row neither black nor white
        const std::size_t row = std::size_t(fb.height / 2) * std::size_t(fb.width);
        for (int x = 0; x < fb.width; ++x) {
            const float v = fb.rgb[3 * (row + std::size_t(x))];
            grey += v > 0.02f && v < 0.98f;
        }
        return grey;
    };
    EXPECT_LE(blurred_pixels(5), 1);
    EXPECT_GE(blurred_pixels(10), 4);
}

// A thick biconvex singlet (radii 60 and -40 mm, 12 mm of index 1.6) with a stop 8 mm behind
// it, its film 60 mm further (a distance focusing replaces).
const std::string kSinglet =
    "# radius thickness eta aperture\n60 12 1.6 30\n-40 8 1 30\n0 60 0 12\n";

// The lens of kSinglet as pbrt-v3's realistic camera makes it (fewer rays bound its pupil).
render::RealisticLens singlet(double focus, double aperture = 12, int pupil_rays = 1 << 14) {
    render::RealisticLens::Settings rs;
    rs.interfaces = render::parse_lens(kSinglet, "lens");
    rs.aperture_diameter = aperture;
    rs.focus_distance = focus;
    rs.film_diagonal = 35;
    rs.xres = 300;
    rs.yres = 200;
    rs.pupil_rays = pupil_rays;
    return render::RealisticLens(rs);
}

// Focused at a distance, rays from the film's centre through a small aperture leave the lens
// towards one point on the axis at that distance in front of the film (pbrt-v3's thick-lens
// focusing: the film at the paraxial image distance behind the rear principal plane).
TEST(RealisticCamera, RaysFromTheFilmsCentreMeetAtTheFocusDistance) {
    for (double focus : {0.5, 2.0, 10.0}) {
        const render::RealisticLens lens = singlet(focus, 2);
        int passed = 0;
        // Near the pupil's middle (spherical aberration moves the marginal rays' crossing).
        for (auto [lu, lv] : {std::pair{0.48, 0.5}, {0.52, 0.5}, {0.5, 0.47}, {0.5, 0.53}}) {
            render::RealisticLens::Ray r;
            if (lens.generate(150, 100, lu, lv, r) == 0) continue;
            ++passed;
            // Where the ray crosses the axis (it lies in a plane through it).
            const double t = std::abs(r.d.x) > std::abs(r.d.y) ? -r.o.x / r.d.x : -r.o.y / r.d.y;
            EXPECT_NEAR(r.o.z + t * r.d.z, focus, 2e-3 * focus) << focus << " " << lu << " " << lv;
        }
        EXPECT_GE(passed, 4) << focus;
    }
    // The film distance: the paraxial image distance from the rear principal plane, also for a
    // focus 10^12 m away (where pbrt-v3's formula cancels to nothing).
    const render::ParaxialLens p = render::paraxial_lens(render::parse_lens(kSinglet, "lens"));
    for (double focus : {2.0, 1e12}) {
        const double image = render::image_distance(p, 1000 * focus);
        EXPECT_NEAR(1000 * singlet(focus).rear_z(), p.rear_principal + image - 20, 1e-3) << focus;
    }
}

// pbrt-v3's exit pupil bounds hold every ray that leaves the lens: film points at random radii,
// rear-element points at random on its disc; each that passes lies within the bound of its
// radius (rotated to the film point's direction: here the film's x axis).
TEST(RealisticCamera, ExitPupilBoundsHoldEveryRayThatPasses) {
    const render::RealisticLens lens = singlet(1.0, 12, 1 << 16);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> U(0, 1);
    const double rear_radius = 0.015, half_diagonal = lens.film_diagonal() / 2;
    int passed = 0;
    for (int k = 0; k < 20000; ++k) {
        const double x = U(rng) * half_diagonal;
        const double a = 2 * render::kPi * U(rng), rr = rear_radius * std::sqrt(U(rng));
        const render::RealisticLens::V3 film{x, 0, 0},
            rear{rr * std::cos(a), rr * std::sin(a), lens.rear_z()};
        if (!lens.trace_from_film({film, {rear.x - x, rear.y, rear.z}}, nullptr)) continue;
        ++passed;
        const int i = std::min(63, static_cast<int>(x / half_diagonal * 64));
        const auto& b = lens.pupil_bounds()[static_cast<std::size_t>(i)];
        EXPECT_TRUE(rear.x >= b.x0 && rear.x <= b.x1 && rear.y >= b.y0 && rear.y <= b.y1)
            << x << " " << rear.x << " " << rear.y;
    }
    EXPECT_GT(passed, 1000);
}

// The weight of a sample is cos^4 theta times its pupil bound's area over the central bound's
// (pbrt-v3's "simpleweighting"): 1 at the centre of the film and pupil; a blocked ray has 0.
TEST(RealisticCamera, SamplesAreWeightedAndBlockedRaysAreZero) {
    const render::RealisticLens lens = singlet(1.0);
    render::RealisticLens::Ray r;
    EXPECT_NEAR(lens.generate(150, 100, 0.5, 0.5, r), 1.0, 1e-6);
    // A corner of the film through its bound's corners: the lens blocks it.
    EXPECT_EQ(lens.generate(0, 0, 0.0, 0.0, r), 0.0);
    // Elsewhere: cos^4 of the ray from the film point to its rear point, times the areas' ratio.
    const double w = lens.generate(40, 30, 0.5, 0.5, r);
    ASSERT_GT(w, 0);
    EXPECT_LT(w, 1);
}

// The camera in the scene: the image the same way up as the perspective camera's (pbrt-v3
// mirrors the film's x so that its lens's inverted image comes out upright), rays leaving the
// front of the lens, and the aperture stop clamped to the file's with pbrt-v3's warning.
TEST(RealisticCamera, FramesTheSceneAsThePerspectiveCamera) {
    LensScene s;
    s.write("singlet.dat", kSinglet);
    std::vector<std::string> warnings;
    auto sc = s.build(
        "\"string lensfile\" \"singlet.dat\" \"float focusdistance\" 1 "
        "\"float aperturediameter\" 4",
        "\"integer xresolution\" 300 \"integer yresolution\" 200", &warnings);
    EXPECT_TRUE(warnings.empty());
    ASSERT_TRUE(sc->camera.realistic);
    const render::CameraRay centre = sc->camera.generate_ray(150, 100);
    EXPECT_NEAR(centre.weight, 1, 1e-5);
    expect_dir(centre.dir, Vec3(0, 0, 1), 1e-4f);
    EXPECT_NEAR(centre.org.z, sc->camera.realistic->front_z(), 1e-6);  // the lens's front
    EXPECT_GT(sc->camera.generate_ray(150, 20).dir.y, 0.05f);          // the top row looks up
    EXPECT_LT(sc->camera.generate_ray(20, 100).dir.x, -0.05f);         // the left column looks left
    // Near the axis, where distortion is small, the perspective camera of the paraxial field.
    const float t = sc->camera.tan_half_fov;
    const render::CameraRay off = sc->camera.generate_ray(170, 110);
    expect_dir(off.dir, Vec3(20.0f / 100 * t, -10.0f / 100 * t, 1), 2e-3f);
    warnings.clear();
    s.build("\"string lensfile\" \"singlet.dat\" \"float aperturediameter\" 20", kFilm100,
            &warnings);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("aperturediameter 20 mm is wider than the lens's aperture stop; "
                               "its 12 mm is used"),
              std::string::npos)
        << warnings[0];
}

// A thick biconvex lens (Hecht's formulas): 1/f = (n-1) (1/R1 - 1/R2 + (n-1) d / (n R1 R2)),
// principal planes -f (n-1) d / (n R2) behind the front vertex and -f (n-1) d / (n R1) behind
// the back one.
TEST(RealisticCamera, ThickLensFocusesFromItsPrincipalPlanes) {
    const double r1 = 60, r2 = -40, d = 12, n = 1.6;
    const double f = 1 / ((n - 1) * (1 / r1 - 1 / r2 + (n - 1) * d / (n * r1 * r2)));
    const double front = -f * (n - 1) * d / (n * r2), rear = d - f * (n - 1) * d / (n * r1);
    const render::ParaxialLens lens =
        render::paraxial_lens(render::parse_lens(element(r1, r2, d, n), "lens"));
    EXPECT_NEAR(lens.focal_length, f, 1e-9);
    EXPECT_NEAR(lens.front_principal, front, 1e-9);
    EXPECT_NEAR(lens.rear_principal, rear, 1e-9);

    // Focused 0.3 m in front of the film: object and image distances add up to 300 mm less the
    // principal planes' separation.
    LensScene s;
    s.write("thick.dat", element(r1, r2, d, n));
    const double sum = 300 - (rear - front);
    const double image = (sum - std::sqrt(sum * sum - 4 * f * sum)) / 2;
    auto sc = s.build("\"string lensfile\" \"thick.dat\" \"float focusdistance\" 0.3", kFilm100);
    EXPECT_NEAR(sc->camera.tan_half_fov, 30 / image, 1e-6);
}

TEST(RealisticCamera, AMissingLensFileIsALocatedError) {
    LensScene s;
    const std::string path = (s.dir.path / "lenses" / "missing.dat").string();
    EXPECT_THROW_MSG(
        s.build("\"string lensfile\" \"lenses/missing.dat\"", kFilm100), pbrt::SceneError,
        s.scene + ":1:20: error: cannot read lens file \"" + path + "\": file not found");
    EXPECT_THROW_MSG(s.build("\"float focusdistance\" 1", kFilm100), pbrt::SceneError,
                     s.scene +
                         ":1:1: error: Camera \"realistic\" needs a \"string lensfile\" "
                         "parameter");
}

TEST(RealisticCamera, MalformedLensFilesAreLocatedErrorsWithTheReason) {
    LensScene s;
    const std::string at =
        s.scene + ":1:20: error: lens file \"" + (s.dir.path / "bad.dat").string();
    auto error_for = [&](const std::string& lens, const std::string& params = "") {
        s.write("bad.dat", lens);
        return test::thrown_text<pbrt::SceneError>(
            [&] { s.build("\"string lensfile\" \"bad.dat\" " + params, kFilm100); });
    };
    EXPECT_EQ(error_for("50 0 1.5 20\n-50 50 0\n"),
              at + "\" holds 7 numbers, not a multiple of 4 (each interface is a curvature "
                   "radius, a thickness, an index of refraction and an aperture diameter)");
    EXPECT_EQ(error_for("# comment\n50 0 1.5 20\n-50 fifty 0 20\n"),
              at + "\", line 3: \"fifty\" is not a number");
    EXPECT_EQ(error_for("50 0 1.5 20\n-50 50 0 1e999\n"),
              at + "\", line 2: \"1e999\" is not a finite number");
    EXPECT_EQ(error_for("50 0 1.5 20\n-50 50 0 nan\n"),
              at + "\", line 2: \"nan\" is not a finite number");
    EXPECT_EQ(error_for("# nothing\n"), at + "\" lists no lens interfaces");
    std::string many;
    for (int k = 0; k < 257; ++k) many += "50 1 1.5 20\n";
    EXPECT_EQ(error_for(many),
              at + "\" lists 257 interfaces; cmam traces lens systems of at most 256");
    // A meniscus of equal radii and no thickness bends no ray.
    EXPECT_EQ(error_for(element(50, 50, 0, 1.5)),
              at + "\": the lens system has no focusing power (its ray-transfer matrix's C is 0): "
                   "an afocal system forms no image on the film");
    EXPECT_EQ(error_for(element(-50, 50, 0, 1.5)),
              at + "\": the lens system diverges (effective focal length -50 mm): it forms no "
                   "image on the film");
    EXPECT_EQ(error_for("50 0 1.5 20\n-50 50 1.5 20\n"),
              at + "\": the last interface's index of refraction is 1.5: the film side of the "
                   "lens system must be air (0 or 1)");
    // The error about focusing is at focusdistance.
    EXPECT_EQ(error_for(element(50, -50, 0, 1.5), "\"float focusdistance\" 0.1"),
              s.scene + ":1:48: error: lens file \"" + (s.dir.path / "bad.dat").string() +
                  "\": the lens system (effective focal length 50 mm) focuses no nearer than "
                  "200 mm in front of the film, and focusdistance asks for 100 mm");
}
