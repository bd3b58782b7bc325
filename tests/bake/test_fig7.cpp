// Numerical NDF filtering reference (TK21 Sec. 4.2 / Fig. 7): the GGX NDF averaged over a Gaussian pixel
// footprint in projected space, by quadrature, on a cylinder-like configuration. Full projected-space
// filtering must fit it better than slope-space filtering at grazing half vectors, and Eq. (9) must approach
// Eq. (8) as the kernel shrinks.
#include "bake/ggx.h"
#include "bake/kernels.h"
#include "bake/methods.h"
#include "bake/peers.h"
#include "reference.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <string>
#include <vector>

namespace specbake {
namespace {

using test::kPi;

double deg(double d) { return d * kPi / 180.0; }

// A pixel on a cylinder (axis along tangent y) whose normal faces the orthographic camera, lit so that the
// half vector is beta away from the view direction (= the normal). One pixel to the right the normal turns
// by delta (delta = pixel size / radius); along the axis nothing changes.
FilterInput<double> cylinder_fragment(double alpha, double beta, double delta) {
    FilterInput<double> in;
    in.alpha = {alpha, alpha};
    in.h = {std::sin(beta), 0, std::cos(beta)};
    in.h_dx = {std::sin(beta - delta), 0, std::cos(beta - delta)};
    in.h_dy = in.h;
    in.n = {0, 0, 1};
    in.n_dx = {std::sin(delta), 0, std::cos(delta)};
    in.n_dy = in.n;
    in.pixel_size = delta;
    in.curvature = 1.0;
    return in;
}

double ggx_at_projected(double x, double y, const Sym2<double>& A) {
    const double r2 = x * x + y * y;
    if (r2 >= 1.0) return 0.0;
    const Vec3<double> h{x, y, std::sqrt(1.0 - r2)};
    // Axis-aligned isotropic GGX, TK21 App. A.2, written out for the reference.
    const double q = (x * x) / A.xx + (y * y) / A.yy + h.z * h.z;
    return 1.0 / (kPi * std::sqrt(A.xx * A.yy) * q * q);
}

// E[f(a)], a ~ N(0, sigma2), by the midpoint rule over +-8 sigma (8000 nodes).
template <class F>
double gaussian_average(double sigma2, F&& f) {
    const int n = 8000;
    const double lim = 8 * std::sqrt(sigma2), step = 2 * lim / n;
    double sum = 0, wsum = 0;
    for (int i = 0; i < n; ++i) {
        const double a = -lim + (i + 0.5) * step;
        const double w = std::exp(-0.5 * a * a / sigma2);
        sum += w * f(a);
        wsum += w;
    }
    return sum / wsum;
}

// Fig. 7 "numerical filtering": E[D(h_xy + a du + b dv)], a, b ~ N(0, sigma^2), by the midpoint rule.
double reference_projected_footprint(const FilterInput<double>& in) {
    const Sym2<double> A{in.alpha.x * in.alpha.x, 0, in.alpha.y * in.alpha.y};
    const double dux = in.h_dx.x - in.h.x, duy = in.h_dx.y - in.h.y;
    return gaussian_average(in.sigma2, [&](double a) { return ggx_at_projected(in.h.x + a * dux, in.h.y + a * duy, A); });
}

// The pixel average with the exact rotation of the normal, E[D(R(delta a) h)], a ~ N(0, sigma^2)
// (the SPEC Sec. 8 ground truth for this fragment).
double reference_rotating_normal(const FilterInput<double>& in, double beta, double delta) {
    const Sym2<double> A{in.alpha.x * in.alpha.x, 0, in.alpha.y * in.alpha.y};
    return gaussian_average(in.sigma2, [&](double a) {
        const double b = beta - delta * a;
        return std::cos(b) > 0 ? ggx_at_projected(std::sin(b), 0, A) : 0.0;
    });
}

double method_ndf(const FilterMethod& m, const FilterInput<double>& in) {
    const Sym2<double> Abar = evaluate(m, in);
    const double tau = std::pow(in.alpha.x * in.alpha.y, 2);  // TK21 App. A.4
    return ggx_ndf(in.h, Abar, tau);
}

double k16_rect_ndf(const FilterInput<double>& in) {
    const Vec2<double> hpp{in.h.x / in.h.z, in.h.y / in.h.z};
    const Vec2<double> dx{in.h_dx.x / in.h_dx.z - hpp.x, in.h_dx.y / in.h_dx.z - hpp.y};
    const Vec2<double> dy{in.h_dy.x / in.h_dy.z - hpp.x, in.h_dy.y / in.h_dy.z - hpp.y};
    const Vec2<double> fp = k16_ggx_rect_footprint(dx, dy, in.alpha, 1.0);
    return k16_ggx_rect_ndf(hpp, in.h, in.alpha, fp);
}

// Two error measures against the reference: the RMS of ln(D / D_ref) over grazing half vectors (the relative
// error where the tail of the NDF is all there is), and the RMS of D - D_ref over the whole sweep divided by
// the reference peak (the error as read off a Fig. 7-style linear plot).
struct Errors {
    double grazing_log_rms = 0;  // beta in [60, 85] degrees
    double plot_rms = 0;         // beta in [0, 85] degrees, relative to max D_ref
    double grazing_log_rms_rot = 0;
    double plot_rms_rot = 0;
};

TEST(Fig7, ProjectedFilteringFitsNumericalReferenceBetterThanSlopeSpace) {
    struct Config {
        double alpha, delta;
    };
    const std::vector<Config> configs{{0.01, 0.02}, {0.05, 0.05}, {0.1, 0.1}, {0.2, 0.05}};
    std::vector<std::string> names;
    for (const FilterMethod& m : filter_methods()) names.emplace_back(m.name);
    names.emplace_back("k16-ggx-rect");
    names.emplace_back("unfiltered");
    for (const Config& c : configs) {
        std::vector<double> betas, ref, ref_rot;
        std::map<std::string, std::vector<double>> ndf;
        for (double beta_deg = 0; beta_deg <= 85.0; beta_deg += 0.25) {
            const double beta = deg(beta_deg);
            const FilterInput<double> in = cylinder_fragment(c.alpha, beta, c.delta);
            betas.push_back(beta_deg);
            ref.push_back(reference_projected_footprint(in));
            ref_rot.push_back(reference_rotating_normal(in, beta, c.delta));
            for (const std::string& name : names) {
                double d;
                if (name == "k16-ggx-rect")
                    d = k16_rect_ndf(in);
                else if (name == "unfiltered")
                    d = ggx_ndf(in.h, Sym2<double>{c.alpha * c.alpha, 0, c.alpha * c.alpha}, 0.0);
                else
                    d = method_ndf(*find_filter_method(name), in);
                ndf[name].push_back(d);
            }
        }
        auto measure = [&](const std::vector<double>& d, const std::vector<double>& r, double& log_rms,
                           double& plot_rms) {
            double sl = 0, sp = 0, peak = 0;
            int nl = 0;
            for (size_t i = 0; i < d.size(); ++i) {
                peak = std::max(peak, r[i]);
                sp += (d[i] - r[i]) * (d[i] - r[i]);
                if (betas[i] >= 60.0) {
                    sl += std::pow(std::log(d[i] / r[i]), 2);
                    nl++;
                }
            }
            log_rms = std::sqrt(sl / nl);
            plot_rms = std::sqrt(sp / d.size()) / peak;
        };
        std::printf("\nFig. 7 comparison: alpha %.2f, normal turns %.3f rad per pixel, sigma^2 = 1/(2 pi)\n", c.alpha,
                    c.delta);
        std::printf("%-17s %16s %16s %16s %16s\n", "method", "grazing ln-RMS", "plot RMS/peak",
                    "(exact) grazing", "(exact) plot");
        std::map<std::string, Errors> err;
        for (const std::string& name : names) {
            Errors& e = err[name];
            measure(ndf[name], ref, e.grazing_log_rms, e.plot_rms);
            measure(ndf[name], ref_rot, e.grazing_log_rms_rot, e.plot_rms_rot);
            std::printf("%-17s %16.4f %16.4f %16.4f %16.4f\n", name.c_str(), e.grazing_log_rms, e.plot_rms,
                        e.grazing_log_rms_rot, e.plot_rms_rot);
        }
        for (const char* better : {"projected", "projected-approx"}) {
            EXPECT_LT(err[better].grazing_log_rms, err["slope"].grazing_log_rms) << better << " alpha " << c.alpha;
            EXPECT_LT(err[better].plot_rms, err["slope"].plot_rms) << better << " alpha " << c.alpha;
            EXPECT_LT(err[better].grazing_log_rms_rot, err["slope"].grazing_log_rms_rot) << better;
        }
        EXPECT_LT(err["projected-aa"].grazing_log_rms, err["slope-aa"].grazing_log_rms) << "alpha " << c.alpha;
        // Eq. (9) stays close to Eq. (8) (TK21 Fig. 7: "the difference ... is negligible").
        EXPECT_LT(std::abs(err["projected-approx"].plot_rms - err["projected"].plot_rms), 0.02) << c.alpha;
    }
}

TEST(Fig7, NumericalReferenceIsConsistent) {
    // The quadrature reproduces the unfiltered NDF for a vanishing footprint and conserves the projected-area
    // normalisation for a wide one (integral over the disk of D is invariant under convolution up to the
    // boundary).
    FilterInput<double> in = cylinder_fragment(0.2, deg(30), 1e-7);
    EXPECT_NEAR(reference_projected_footprint(in), ggx_ndf(in.h, Sym2<double>{0.04, 0, 0.04}, 0.0), 1e-6);
    EXPECT_NEAR(reference_rotating_normal(in, deg(30), 1e-7), ggx_ndf(in.h, Sym2<double>{0.04, 0, 0.04}, 0.0), 1e-6);
}

TEST(Fig7, Eq9ApproachesEq8AsTheKernelShrinks) {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int k = 0; k < 200; ++k) {
        const double ax = 0.01 + 0.09 * u(rng), ay = 0.01 + 0.09 * u(rng);
        const Vec2<double> r2{ax * ax, ay * ay};
        const Vec2<double> du{u(rng) - 0.5, u(rng) - 0.5}, dv{u(rng) - 0.5, u(rng) - 0.5};
        double previous = 0;
        for (double eps : {1e-1, 1e-2, 1e-3, 1e-4}) {
            const Vec2<double> su = eps * du, sv = eps * dv;
            const Sym2<double> eq8 = filter_projected(r2, su, sv, kDefaultSigma2);
            const Sym2<double> eq9 = filter_non_axis_aligned(r2, su, sv, kDefaultSigma2);
            const double diff = std::sqrt(std::pow(eq9.xx - eq8.xx, 2) + 2 * std::pow(eq9.xy - eq8.xy, 2) +
                                          std::pow(eq9.yy - eq8.yy, 2));
            const Sym2<double> kernel = kernel_roughness(su, sv, kDefaultSigma2);
            const double knorm = std::sqrt(kernel.xx * kernel.xx + 2 * kernel.xy * kernel.xy + kernel.yy * kernel.yy);
            // First order: Eq. (8) - A = (I - A) 2 Sigma (I - A), so Eq. (9) overshoots by about 2 a_max 2 Sigma.
            EXPECT_LE(diff, (2.2 * std::max(r2.x, r2.y) + 50 * knorm) * knorm) << "eps " << eps;
            if (previous > 0) EXPECT_LT(diff, 0.02 * previous) << "eps " << eps;  // shrinks like eps^2
            previous = diff;
        }
    }
}

}  // namespace
}  // namespace specbake
