// render — the first-order (paraxial) optics of a pbrt-v3 "realistic" camera's lens system: its
// lens file, its effective focal length and principal planes from ray-transfer matrices, and the
// film distance that focuses it (algorithms.md §7.2). The scene builder renders the camera as
// the pinhole these give.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

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

}  // namespace cmam::render
