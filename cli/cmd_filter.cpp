// specbake filter: evaluates every roughness-filtering method of bake/methods.h on one fragment and
// prints a table or JSON. Only argument parsing and formatting live here.
#include "cli/command.h"

#include "bake/methods.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace specbake::cli {
namespace {

// Default fragment: a cylinder of radius 1 seen so that the half vector is 70 degrees off the normal
// (grazing). One pixel step in x turns the shading frame by kArcPerPixel radians around the cylinder
// axis (tangent-space y); the step in y moves along the axis and turns the half vector slightly through
// the perspective change of the view direction.
constexpr double kHalfVectorTilt = 1.2217304763960306;  // 70 degrees
constexpr double kArcPerPixel = 0.05;
constexpr double kViewTurnPerPixel = 0.005;

std::vector<double> tilted(double angle_xz, double angle_yz) {
    const double x = std::sin(angle_xz) * std::cos(angle_yz);
    const double y = std::sin(angle_yz);
    const double z = std::cos(angle_xz) * std::cos(angle_yz);
    return {x, y, z};
}

struct FilterOptions {
    std::vector<double> alpha{0.05};
    std::vector<double> h = tilted(kHalfVectorTilt, 0.0);
    std::vector<double> h_dx = tilted(kHalfVectorTilt - kArcPerPixel, 0.0);
    std::vector<double> h_dy = tilted(kHalfVectorTilt, kViewTurnPerPixel);
    std::vector<double> n{0.0, 0.0, 1.0};
    std::vector<double> n_dx = tilted(kArcPerPixel, 0.0);
    std::vector<double> n_dy{0.0, 0.0, 1.0};
    double sigma2 = kDefaultSigma2;
    double kappa = kDefaultKappa;
    double pixel_size = kArcPerPixel;
    double curvature = 1.0;
    std::vector<std::string> methods;
    bool json = false;
};

std::string format_vector(const std::vector<double>& v) {
    std::string s;
    for (double x : v) s += (s.empty() ? "" : ",") + std::to_string(x);
    return s;
}

// Validates a direction option and returns it normalised.
bool read_direction(const std::vector<double>& v, const char* flag, Vec3<double>& out) {
    const Vec3<double> d{v[0], v[1], v[2]};
    const double len = length(d);
    if (!std::isfinite(len) || len == 0.0) {
        print_error(std::string(flag) + " must be a finite non-zero vector X,Y,Z");
        return false;
    }
    out = normalize(d);
    return true;
}

int run_filter(const FilterOptions& o) {
    FilterInput<double> in;
    if (o.alpha.empty() || o.alpha.size() > 2) {
        print_error("--alpha takes AX or AX,AY");
        return kExitUsage;
    }
    in.alpha = {o.alpha[0], o.alpha.size() == 2 ? o.alpha[1] : o.alpha[0]};
    for (double a : {in.alpha.x, in.alpha.y}) {
        if (!(a >= 0.0 && a <= 1.0)) {
            print_error("--alpha must lie in [0, 1] (alpha = perceptual roughness squared)");
            return kExitUsage;
        }
    }
    if (!read_direction(o.h, "--h", in.h) || !read_direction(o.h_dx, "--h-dx", in.h_dx) ||
        !read_direction(o.h_dy, "--h-dy", in.h_dy) || !read_direction(o.n, "--n", in.n) ||
        !read_direction(o.n_dx, "--n-dx", in.n_dx) || !read_direction(o.n_dy, "--n-dy", in.n_dy))
        return kExitUsage;
    if (!(std::isfinite(o.sigma2) && o.sigma2 >= 0.0) || !(o.kappa >= 0.0) ||
        !(std::isfinite(o.pixel_size) && o.pixel_size >= 0.0) || !std::isfinite(o.curvature)) {
        print_error("--sigma2, --kappa and --pixel-size must be non-negative and finite (--kappa may be inf)");
        return kExitUsage;
    }
    in.sigma2 = o.sigma2;
    in.kappa = o.kappa;
    in.pixel_size = o.pixel_size;
    in.curvature = o.curvature;

    std::vector<const FilterMethod*> selected;
    if (o.methods.empty()) {
        for (const FilterMethod& m : filter_methods()) selected.push_back(&m);
    } else {
        for (const std::string& name : o.methods) {
            const Result<Sym2<double>> r = evaluate_method(name, in);
            if (!r) {
                print_error(r.error().message);
                return kExitUsage;
            }
            selected.push_back(find_filter_method(name));
        }
    }

    if (o.json) {
        nlohmann::json results = nlohmann::json::array();
        for (const FilterMethod* m : selected) {
            const Sym2<double> A = evaluate(*m, in);
            results.push_back({{"method", m->name},
                               {"source", m->source},
                               {"A", {{A.xx, A.xy}, {A.xy, A.yy}}}});
        }
        const nlohmann::json input = {
            {"alpha", {in.alpha.x, in.alpha.y}},
            {"h", {in.h.x, in.h.y, in.h.z}},
            {"h_dx", {in.h_dx.x, in.h_dx.y, in.h_dx.z}},
            {"h_dy", {in.h_dy.x, in.h_dy.y, in.h_dy.z}},
            {"n", {in.n.x, in.n.y, in.n.z}},
            {"n_dx", {in.n_dx.x, in.n_dx.y, in.n_dx.z}},
            {"n_dy", {in.n_dy.x, in.n_dy.y, in.n_dy.z}},
            {"sigma2", in.sigma2},
            {"kappa", std::isfinite(in.kappa) ? nlohmann::json(in.kappa) : nlohmann::json("inf")},
            {"pixel_size", in.pixel_size},
            {"curvature", in.curvature}};
        std::printf("%s\n", nlohmann::json{{"input", input}, {"results", results}}.dump(2).c_str());
        return kExitOk;
    }

    std::printf("alpha = (%g, %g), A = diag(%g, %g), sigma2 = %g, kappa = %g\n", in.alpha.x, in.alpha.y,
                in.alpha.x * in.alpha.x, in.alpha.y * in.alpha.y, in.sigma2, in.kappa);
    std::printf("h = (%.6f, %.6f, %.6f)   n = (%.6f, %.6f, %.6f)\n\n", in.h.x, in.h.y, in.h.z, in.n.x, in.n.y,
                in.n.z);
    std::printf("%-17s %12s %12s %12s %12s  %s\n", "method", "A11", "A12", "A22", "det", "source");
    for (const FilterMethod* m : selected) {
        const Sym2<double> A = evaluate(*m, in);
        std::printf("%-17s %12.6g %12.6g %12.6g %12.6g  %s\n", std::string(m->name).c_str(), A.xx, A.xy, A.yy,
                    det(A), std::string(m->source).c_str());
    }
    return kExitOk;
}

}  // namespace

void add_filter_command(CLI::App& app, std::function<int()>& run) {
    auto opts = std::make_shared<FilterOptions>();
    auto* sub = app.add_subcommand(
        "filter",
        "Evaluate every NDF-filtering method on one fragment and print the filtered roughness matrices");
    sub->add_option("--alpha", opts->alpha, "Roughness alpha = r^2, AX or AX,AY in [0, 1]")
        ->delimiter(',')
        ->expected(1, 2)
        ->default_str(format_vector(opts->alpha));
    const auto vec3 = [&](const char* flag, std::vector<double>& v, const char* what) {
        sub->add_option(flag, v, what)->delimiter(',')->expected(3)->default_str(format_vector(v));
    };
    vec3("--h", opts->h, "Tangent-space unit half vector at the fragment, X,Y,Z");
    vec3("--h-dx", opts->h_dx, "Half vector at the right neighbour (derivative = neighbour - fragment)");
    vec3("--h-dy", opts->h_dy, "Half vector at the down neighbour");
    vec3("--n", opts->n, "World-space unit normal at the fragment (isotropic methods)");
    vec3("--n-dx", opts->n_dx, "World-space normal at the right neighbour");
    vec3("--n-dy", opts->n_dy, "World-space normal at the down neighbour");
    sub->add_option("--sigma2", opts->sigma2, "Pixel-filter variance in pixels^2 (TK21 App. B)")->capture_default_str();
    sub->add_option("--kappa", opts->kappa, "Kernel clamp of the clamped methods (inf: no clamp)")
        ->capture_default_str();
    sub->add_option("--pixel-size", opts->pixel_size, "World-space pixel size (varef-curvature)")
        ->capture_default_str();
    sub->add_option("--curvature", opts->curvature, "Curvature 1/radius in 1/world length (varef-curvature)")
        ->capture_default_str();
    sub->add_option("--method", opts->methods, "Evaluate only these methods (repeatable)");
    sub->add_flag("--json", opts->json, "Print JSON: {\"input\": ..., \"results\": [{method, source, A}, ...]}");
    sub->footer(
        "Vectors are normalised before use. A is the filtered roughness matrix in squared-roughness units\n"
        "(alpha^2); isotropic methods add one kernel to both axes.\n"
        "Without arguments: a grazing fragment on a cylinder of radius 1 (half vector 70 degrees off the\n"
        "normal, 0.05 rad of arc per pixel, alpha 0.05).\n\n"
        "Examples:\n"
        "  specbake filter\n"
        "  specbake filter --json\n"
        "  specbake filter --alpha 0.1,0.02 --h 0.6,0,0.8 --h-dx 0.64,0,0.77 --h-dy 0.6,0.02,0.8\n"
        "  specbake filter --method projected --method projected-approx --kappa inf");
    sub->callback([&run, opts] { run = [opts] { return run_filter(*opts); }; });
}

}  // namespace specbake::cli
