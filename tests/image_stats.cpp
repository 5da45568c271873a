// image_stats IMAGE: prints "width height mean stddev" of an image's luminance (as stored), for
// shell-level tests such as "the report's screenshot is not blank".
#include <cmath>
#include <cstdio>

#include "render/image_io.h"

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: image_stats IMAGE\n");
        return 2;
    }
    try {
        cmam::render::RawImage img = cmam::render::read_image(argv[1]);
        double sum = 0, sum2 = 0;
        const std::size_t n = static_cast<std::size_t>(img.width) * img.height;
        for (std::size_t p = 0; p < n; ++p) {
            const float* px = &img.pixels[p * img.channels];
            double y = img.channels >= 3 ? 0.2126 * px[0] + 0.7152 * px[1] + 0.0722 * px[2] : px[0];
            sum += y;
            sum2 += y * y;
        }
        double mean = sum / n;
        std::printf("%d %d %.6f %.6f\n", img.width, img.height, mean,
                    std::sqrt(std::max(0.0, sum2 / n - mean * mean)));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "image_stats: %s\n", e.what());
        return 1;
    }
    return 0;
}
