// cmam — the command line's changes to a scene's film, --resolution and --crop, which render and
// eval share.
#pragma once

#include <string>
#include <vector>

#include "pbrt/error.h"
#include "pbrt/scene_desc.h"

namespace cmam::app {

/// What --resolution and --crop ask of a scene's film. The text is checked when it is given
/// (UsageError naming the option), before any scene is read; apply() changes one scene's film.
class FilmOverrides {
  public:
    /// `resolution`: "WIDTHxHEIGHT", or "WIDTH" alone to keep each scene's aspect ratio (and so
    /// its camera's framing); `crop`: "X0,X1,Y0,Y1", fractions of the image from the top left
    /// (the Film's cropwindow, replacing the scene's). Empty strings change nothing.
    FilmOverrides(const std::string& resolution, const std::string& crop);

    bool empty() const { return m_width == 0 && m_crop.empty(); }

    /// The scene's film as if its Film statement said so. Another aspect ratio than the scene's
    /// frames more or less of it, as in pbrt-v3, and `warn` receives a warning saying so.
    /// Throws UsageError when a width alone gives this scene a resolution above cmam's limits.
    void apply(pbrt::SceneDesc& desc, const pbrt::WarningSink& warn) const;

  private:
    long long m_width = 0, m_height = 0;  // 0: unchanged; a height of 0: the scene's aspect
    std::vector<double> m_crop;           // empty: unchanged
};

}  // namespace cmam::app
