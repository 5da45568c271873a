// fuzz — Fourier BSDF tables on arbitrary bytes: render::read_fourier_table returns a table or
// throws RenderError, and a table read is evaluated, its density taken and sampled in a few
// directions (whatever its nodes and coefficients, nothing is read outside it).
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz/fuzz_util.h"
#include "render/error.h"
#include "render/fourier.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
    static const std::string path = cmam::fuzz::scratch_path(".bsdf");
    cmam::fuzz::write_file(path, data, size);
    using namespace cmam::render;
    FourierTable t;
    try {
        t = read_fourier_table(path);
    } catch (const RenderError&) {
        return 0;
    }
    const Vec3 dirs[] = {{0, 0, 1}, {0.6f, 0, 0.8f}, {0, -0.8f, -0.6f}, {1, 0, 0}};
    for (const Vec3& wo : dirs)
        for (const Vec3& wi : dirs) {
            (void)fourier_f(t, wo, wi);
            (void)fourier_pdf(t, wo, wi);
        }
    for (const Vec3& wo : dirs)
        for (float u : {0.0f, 0.3f, 0.5f, 0.99f}) (void)fourier_sample(t, wo, u, 1 - u);
    return 0;
}
