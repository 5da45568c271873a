// render — a pbrt-v3 "realistic" camera's lens system: its lens file, its first-order
// (paraxial) optics from ray-transfer matrices (algorithms.md §7.2), and the camera itself, rays
// traced from the film through the lens's spherical interfaces and aperture stop as pbrt-v3's
// RealisticCamera traces them (algorithms.md §7.3).
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "render/math.h"

namespace cmam::render {

/// One interface of a lens system as a pbrt-v3 lens file lists it, lengths in mm. A spherical
/// surface whose curvature radius is `radius` (positive: its centre lies on the film side), or
/// the planar aperture stop when `radius` is 0. `thickness` is the distance to the next interface
/// (from the last one, to the film); `eta` the index of refraction of the medium behind it, towards
/// the film (0 is air); `aperture` its diameter.
struct LensInterface {
    double radius = 0, thickness = 0, eta = 0, aperture = 0;
};

/// Largest lens file read (lens files list a few dozen numbers).
constexpr std::size_t kMaxLensFileBytes = std::size_t(1) << 20;

/// The interfaces listed by `text`, a lens file: numbers separated by white space, '#' to the end
/// of its line a comment, four per interface from the scene side to the film side. Throws
/// RenderError naming `subject` (`lens file "path"`) with the reason: a word that is not a
/// finite number (with its line), a count that is not a multiple of 4, no interfaces.
std::vector<LensInterface> parse_lens(std::string_view text, const std::string& subject);

/// The interfaces of the lens file at `path`. Throws RenderError naming the file: "cannot read
/// lens file …" when it cannot be read, or parse_lens's reason.
std::vector<LensInterface> read_lens_file(const std::string& path);

/// A converging lens system's paraxial description, in air on both sides. Positions are in mm
/// along the axis from the first interface towards the film.
struct ParaxialLens {
    double focal_length = 0;     // effective focal length, -1/C (positive)
    double front_principal = 0;  // the object-side principal plane
    double rear_principal = 0;   // the image-side principal plane
};

/// The system matrix of `lens` (the last interface's thickness, the film distance, left out)
/// reduced to its focal length and principal planes. Throws RenderError when the system forms no
/// image on the film: no focusing power (C = 0 to rounding: an afocal system), a diverging one
/// (C > 0), or a film side that is not air.
ParaxialLens paraxial_lens(const std::vector<LensInterface>& lens);

/// The distance from the rear principal plane to the film at which `lens` focuses on a point
/// `focus_distance` mm in front of the film, as pbrt-v3 measures it: the thin-lens equation in
/// the principal planes' frame, the root nearer the focal length. Throws RenderError when the
/// system cannot focus that near.
double image_distance(const ParaxialLens& lens, double focus_distance);

/// pbrt-v3's realistic camera (algorithms.md §7.3), in its units (metres) and its camera space
/// (left-handed, looking along +z, the film at z = 0 and the lens in front of it). The lens
/// system is focused as pbrt-v3 focuses it (its thick-lens approximation moves the last
/// interface), and the exit pupil is bounded, as pbrt-v3 bounds it, at 64 distances from the
/// film's centre by 2^20 rays each.
class RealisticLens {
  public:
    struct Settings {
        std::vector<LensInterface> interfaces;  // as the lens file lists them (mm)
        double aperture_diameter = 1;           // mm: the stop's, at most the file's
        double focus_distance = 10;             // m, in front of the film
        double film_diagonal = 35;              // mm
        int xres = 1, yres = 1;                 // the film's full resolution
        bool simple_weighting = true;
        int pupil_rays = 1 << 20;  // per bound (pbrt-v3's); fewer only for tests
    };
    /// Throws RenderError when the lens cannot be focused at that distance or a ray parallel to
    /// the axis does not pass (the stop too small).
    explicit RealisticLens(const Settings& s);

    using V3 = Vec3d;
    struct Ray {
        V3 o, d;
    };
    /// The ray through raster position (px, py) of the full film from the exit-pupil sample
    /// (lu, lv) in [0,1)^2, in camera space (d not normalised), and its weight: pbrt-v3's
    /// cos^4 theta times the pupil bound's area over the central one's ("simpleweighting"), or
    /// over the rear element's distance squared. 0 when the lens blocks it (`ray` is then
    /// unspecified).
    double generate(double px, double py, double lu, double lv, Ray& ray) const;
    /// A ray from the film side (camera space) through the interfaces; false when an aperture
    /// or total internal reflection stops it.
    bool trace_from_film(const Ray& in, Ray* out) const;
    bool trace_from_scene(const Ray& in, Ray* out) const;

    struct Bounds {
        double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
        double area() const { return (x1 - x0) * (y1 - y0); }
    };
    static constexpr int kPupilBounds = 64;
    static constexpr std::size_t kMaxInterfaces = 256;
    const std::array<Bounds, kPupilBounds>& pupil_bounds() const { return m_pupil; }
    double rear_z() const { return m_el.back().thickness; }  // the film's distance to the lens
    double front_z() const;                                  // to its front interface
    double film_diagonal() const { return m_diagonal; }      // m
    /// What the aperture stop's diameter was clamped to (the file's), or 0.
    double clamped_aperture() const { return m_clamped; }

  private:
    struct Element {
        double radius, thickness, eta, aperture_radius;  // m; eta 0 is air
    };
    std::vector<Element> m_el;
    std::array<Bounds, kPupilBounds> m_pupil{};
    double m_diagonal = 0.035, m_half_x = 0, m_half_y = 0;
    int m_xres = 1, m_yres = 1;
    bool m_simple = true;
    double m_clamped = 0;
    Bounds bound_exit_pupil(double x0, double x1, int rays) const;
    static bool pass(const Element& e, double z, double eta_i, double eta_t, Ray& r);
};

}  // namespace cmam::render
