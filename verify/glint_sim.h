// Glint simulation of `specbake verify --builtin glitter-sphere | glitter-plane`: the C21 candidates
// evaluated on the CPU with the C++ twin of the include's glint path (bake/glint_model.h, checked against
// the GLSL include on llvmpipe), against a reference integrated over each pixel with the Gaussian pixel
// filter, the cell footprint frozen to the pixel's and no filtering (the reference of C21 Sec. 6).
#pragma once

#include "bake/glint_dictionary.h"
#include "core/result.h"

#include <cstdint>
#include <string>
#include <vector>

namespace specbake::verify {

struct GlintSimSettings {
    std::string scene = "glitter-sphere";  // or "glitter-plane" (anisotropic, rotated normal map)
    int size = 64;                         // pixels per side
    int reference_spp = 1024;              // Gaussian-distributed sub-pixel samples of the reference
    int frames = 4;                        // slow motion: the surface moves by 1/4 pixel per frame
    double alpha = 0.1;                    // Beckmann alpha of the material (sigma = alpha / sqrt 2)
    double log_density = 15.0;
    double relative_area = 1.0;
};

struct GlintSimRow {
    std::string candidate;
    double rmse_percent = 0.0;  // RMSE over the covered pixels, relative to the reference's mean, x100
    double flicker = 0.0;       // mean |frame-to-frame change of the error| relative to the reference's mean
    double energy = 0.0;        // sum of the candidate / sum of the reference
    double cells = 0.0;         // per pixel and light: bounding-box cells visited (both levels)
    double fetches = 0.0;       // per pixel and light: dictionary texture fetches
};

struct GlintSimReport {
    std::vector<GlintSimRow> rows;
    int pixels = 0;             // covered pixels per frame
    double reference_mean = 0.0;
};

// Candidates: smooth (analytic Beckmann), c20 (glints without anti-aliasing), ggaa (C21, s_K = 0.5),
// ggaa-sk1; on the plane also ggaa+lean-norho and ggaa+lean (normal map filtered over the pixel footprint
// as ideal LEAN mips, with and without the correlation rho of Eq. 18) and ggaa (no LEAN: the normal map at
// the pixel centre).
Result<GlintSimReport> run_glint_sim(const GlintDictionary& dictionary, const GlintSimSettings& settings);

}  // namespace specbake::verify
