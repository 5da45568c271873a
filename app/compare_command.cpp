// cmam compare: the error of an image against a reference, in linear RGB.
#include <cmam/texture/image.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "app/command.h"
#include "app/common.h"
#include "eval/metrics.h"
#include "render/image_io.h"

namespace cmam::app {

namespace {

struct CompareArgs {
    std::string reference, image;
    bool json = false;
};

// Three linear channels per pixel: 8-bit images are sRGB-decoded, one channel is grey.
std::vector<float> linear_rgb(const render::RawImage& r) {
    std::vector<float> v(static_cast<std::size_t>(r.width) * r.height * 3);
    for (std::size_t p = 0; p < v.size() / 3; ++p)
        for (int c = 0; c < 3; ++c) {
            float x = r.pixels[p * r.channels + std::min(c, r.channels - 1)];
            v[3 * p + c] = r.is_8bit ? texture::srgb_to_linear(x) : x;
        }
    return v;
}

int run_compare(const CompareArgs& a) {
    render::RawImage ref = render::read_image(a.reference), img = render::read_image(a.image);
    if (ref.width != img.width || ref.height != img.height)
        throw UsageError("\"" + a.image + "\" is " + std::to_string(img.width) + "x" +
                         std::to_string(img.height) + ", the reference is " +
                         std::to_string(ref.width) + "x" + std::to_string(ref.height));
    eval::ErrorStats s = eval::compare(linear_rgb(ref), linear_rgb(img));
    if (a.json)
        std::printf(
            "{\"reference\": \"%s\", \"image\": \"%s\", \"rmse\": %s, \"relative_rmse\": %s, "
            "\"psnr\": %s, \"pixels\": %zu}\n",
            json_escape(a.reference).c_str(), json_escape(a.image).c_str(),
            json_number(s.rmse).c_str(), json_number(s.relative_rmse).c_str(),
            json_number(s.psnr).c_str(), s.pixels);
    else
        std::printf("%s vs %s: RMSE %.6f (%.2f%% of the reference mean %.6f), PSNR %.2f dB\n",
                    a.image.c_str(), a.reference.c_str(), s.rmse, 100 * s.relative_rmse,
                    s.reference_mean, s.psnr);
    return 0;
}

void add_compare_options(CLI::App& cmd, CompareArgs& a) {
    cmd.add_option("reference", a.reference, "Reference image")->required();
    cmd.add_option("image", a.image, "Image to measure")->required();
    cmd.add_flag("--json", a.json, "One JSON object on stdout");
}

}  // namespace

Command add_compare_command(CLI::App& app) {
    return make_command(app, "compare", "Error of an image against a reference (linear RGB)",
                        add_compare_options, run_compare);
}

}  // namespace cmam::app
