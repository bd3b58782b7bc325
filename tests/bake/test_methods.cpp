// Every method of the table against an independent double-precision evaluation (explicit finite
// differences, Eigen inverses and eigenvalues) on random fragments, in float and double.
#include "bake/kernels.h"
#include "bake/methods.h"
#include "bake/peers.h"
#include "reference.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <string>

namespace specbake {
namespace {

using Eigen::Matrix2d;
using Eigen::Vector2d;
using Eigen::Vector3d;

Vector3d v3(const Vec3<double>& v) { return {v.x, v.y, v.z}; }

// Derivative matrix D = [du; dv] (rows) of a 2D map of the half vector between fragment and neighbours.
template <class Map>
Matrix2d derivative_rows(const FilterInput<double>& in, Map map) {
    const Vector2d c = map(v3(in.h));
    Matrix2d D;
    D.row(0) = (map(v3(in.h_dx)) - c).transpose();
    D.row(1) = (map(v3(in.h_dy)) - c).transpose();
    return D;
}

Vector2d slope_of(const Vector3d& h) { return -h.head<2>() / std::abs(h.z()); }
Vector2d projection_of(const Vector3d& h) { return h.head<2>(); }

double clamp01(double x) { return std::min(1.0, std::max(0.0, x)); }

Matrix2d reference(const std::string& method, const FilterInput<double>& in) {
    const Matrix2d A = Vector2d(in.alpha.x * in.alpha.x, in.alpha.y * in.alpha.y).asDiagonal();
    const Matrix2d I = Matrix2d::Identity();
    auto non_axis = [&](const Matrix2d& D) -> Matrix2d { return A + 2 * in.sigma2 * D.transpose() * D; };
    auto axis = [&](const Matrix2d& D) -> Matrix2d {
        const Vector2d w = D.cwiseAbs().colwise().sum();  // fwidth = |ddx| + |ddy|
        Matrix2d out = Matrix2d::Zero();
        for (int k = 0; k < 2; ++k) out(k, k) = clamp01(A(k, k) + std::min(2 * in.sigma2 * w(k) * w(k), in.kappa));
        return out;
    };
    if (method == "slope") return non_axis(derivative_rows(in, slope_of));
    if (method == "slope-aa") return axis(derivative_rows(in, slope_of));
    if (method == "projected-approx") return non_axis(derivative_rows(in, projection_of));
    if (method == "projected-aa") return axis(derivative_rows(in, projection_of));
    if (method == "projected") {
        const Matrix2d D = derivative_rows(in, projection_of);
        const Matrix2d B = (A.inverse() - I).inverse();              // TK21 Eq. (4)
        const Matrix2d Bbar = B + 2 * in.sigma2 * D.transpose() * D;  // Eq. (6)
        return (Bbar.inverse() + I).inverse();                       // Eq. (7)
    }
    // Normal-based methods: eigenvalues of Sigma = sigma^2 N^T N, N = [dn_u dn_v] (3x2).
    Eigen::Matrix<double, 3, 2> N;
    N.col(0) = v3(in.n_dx) - v3(in.n);
    N.col(1) = v3(in.n_dy) - v3(in.n);
    const Eigen::SelfAdjointEigenSolver<Matrix2d> eig(in.sigma2 * N.transpose() * N);
    const double lmin = eig.eigenvalues()(0), lmax = eig.eigenvalues()(1);
    auto iso = [&](double kernel) -> Matrix2d {
        return Vector2d(clamp01(A(0, 0) + std::min(kernel, in.kappa)), clamp01(A(1, 1) + std::min(kernel, in.kappa)))
            .asDiagonal();
    };
    if (method == "iso-max") return iso(2 * lmax);                 // TK21 Eq. (10)
    if (method == "iso-sum") return iso(2 * (lmin + lmax));        // Eq. (13)
    if (method == "iso-mean") return iso(lmin + lmax);             // Eq. (14)
    auto varef = [&](double variance) -> Matrix2d {
        Vector2d out;
        for (int k = 0; k < 2; ++k) {
            const double r = std::clamp(std::sqrt(std::sqrt(A(k, k)) + variance), 0.04, 1.0);
            out(k) = r * r * r * r;
        }
        return out.asDiagonal();
    };
    if (method == "varef-screen")
        return varef(std::min(50.0 * std::max(N.col(0).squaredNorm(), N.col(1).squaredNorm()), 0.1));
    if (method == "varef-curvature") {
        const double x = in.pixel_size * in.curvature;
        return varef(std::min(50.0 * x * x, 0.1));
    }
    ADD_FAILURE() << "no reference for " << method;
    return Matrix2d::Zero();
}

Vec3<double> random_unit_upper(std::mt19937_64& rng, double min_z) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double z = min_z + (1.0 - min_z) * u(rng);
    const double phi = 2 * test::kPi * u(rng);
    const double s = std::sqrt(1 - z * z);
    return {s * std::cos(phi), s * std::sin(phi), z};
}

Vec3<double> perturbed(std::mt19937_64& rng, const Vec3<double>& v, double scale) {
    std::normal_distribution<double> g(0.0, scale);
    return normalize(Vec3<double>{v.x + g(rng), v.y + g(rng), v.z + g(rng)});
}

FilterInput<double> random_input(std::mt19937_64& rng, double min_perturbation) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    FilterInput<double> in;
    in.alpha = {0.01 + 0.97 * u(rng), 0.01 + 0.97 * u(rng)};
    in.h = random_unit_upper(rng, 0.2);
    const double scale = min_perturbation * std::pow(0.3 / min_perturbation, u(rng));
    in.h_dx = perturbed(rng, in.h, scale);
    in.h_dy = perturbed(rng, in.h, scale * u(rng));
    if (in.h_dx.z <= 0.05) in.h_dx = in.h;
    if (in.h_dy.z <= 0.05) in.h_dy = in.h;
    in.n = random_unit_upper(rng, -1.0);
    in.n_dx = perturbed(rng, in.n, scale);
    in.n_dy = perturbed(rng, in.n, scale * u(rng));
    in.sigma2 = kDefaultSigma2 * (0.5 + u(rng));
    in.kappa = 0.02 + u(rng);
    in.pixel_size = 0.1 * u(rng);
    in.curvature = 10 * u(rng);
    return in;
}

FilterInput<float> to_float(const FilterInput<double>& d) {
    auto f3 = [](const Vec3<double>& v) { return Vec3<float>{float(v.x), float(v.y), float(v.z)}; };
    FilterInput<float> f;
    f.alpha = {float(d.alpha.x), float(d.alpha.y)};
    f.h = f3(d.h), f.h_dx = f3(d.h_dx), f.h_dy = f3(d.h_dy);
    f.n = f3(d.n), f.n_dx = f3(d.n_dx), f.n_dy = f3(d.n_dy);
    f.sigma2 = float(d.sigma2), f.kappa = float(d.kappa), f.pixel_size = float(d.pixel_size);
    f.curvature = float(d.curvature);
    return f;
}

// The float input rounded back to double, so the reference sees what the float evaluation sees.
FilterInput<double> to_double(const FilterInput<float>& f) {
    auto d3 = [](const Vec3<float>& v) { return Vec3<double>{v.x, v.y, v.z}; };
    FilterInput<double> d;
    d.alpha = {f.alpha.x, f.alpha.y};
    d.h = d3(f.h), d.h_dx = d3(f.h_dx), d.h_dy = d3(f.h_dy);
    d.n = d3(f.n), d.n_dx = d3(f.n_dx), d.n_dy = d3(f.n_dy);
    d.sigma2 = f.sigma2, d.kappa = f.kappa, d.pixel_size = f.pixel_size, d.curvature = f.curvature;
    return d;
}

TEST(Methods, TableListsTheIssueNamesWithSources) {
    std::vector<std::string> names;
    for (const FilterMethod& m : filter_methods()) {
        names.emplace_back(m.name);
        EXPECT_FALSE(m.source.empty());
        EXPECT_EQ(find_filter_method(m.name), &m);
    }
    const std::vector<std::string> expected{"slope",   "slope-aa", "projected-approx", "projected-aa",
                                            "projected", "iso-max", "iso-sum",         "iso-mean",
                                            "varef-screen", "varef-curvature"};
    EXPECT_EQ(names, expected);
    EXPECT_EQ(find_filter_method("nope"), nullptr);
    const auto r = evaluate_method("nope", FilterInput<double>{});
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("projected-approx"), std::string::npos);
}

TEST(Methods, MatchIndependentReferenceInDouble) {
    std::mt19937_64 rng(5);
    for (int k = 0; k < 3000; ++k) {
        const FilterInput<double> in = random_input(rng, 1e-6);
        for (const FilterMethod& m : filter_methods()) {
            const Matrix2d want = reference(std::string(m.name), in);
            const Sym2<double> got = evaluate(m, in);
            const double tol = 1e-9 * (1 + want.norm());
            ASSERT_NEAR(got.xx, want(0, 0), tol) << m.name << " sample " << k;
            ASSERT_NEAR(got.xy, want(0, 1), tol) << m.name << " sample " << k;
            ASSERT_NEAR(got.yy, want(1, 1), tol) << m.name << " sample " << k;
        }
    }
}

TEST(Methods, FloatMatchesReferenceOfRoundedInput) {
    std::mt19937_64 rng(6);
    for (int k = 0; k < 3000; ++k) {
        const FilterInput<float> in = to_float(random_input(rng, 1e-2));
        const FilterInput<double> ind = to_double(in);
        for (const FilterMethod& m : filter_methods()) {
            const Matrix2d want = reference(std::string(m.name), ind);
            const Sym2<double> got = test::to_sym(evaluate(m, in));
            // Derivatives are differences of nearby float values: relative error ~ 1e-7 / 1e-2 per entry.
            const double tol = 2e-4 * (1e-3 + want.norm());
            ASSERT_NEAR(got.xx, want(0, 0), tol) << m.name << " sample " << k;
            ASSERT_NEAR(got.xy, want(0, 1), tol) << m.name << " sample " << k;
            ASSERT_NEAR(got.yy, want(1, 1), tol) << m.name << " sample " << k;
        }
    }
}

TEST(Methods, ProjectedIsotropicCaseIsTheSpecClosedForm) {
    // An isotropic kernel (orthogonal derivatives of equal length) on an isotropic material: Listing 1 must
    // reduce to SPEC Sec. 3's a' = (a + t (1 - a)) / (1 + t (1 - a)) with t = 2 sigma^2 |d|^2.
    for (double alpha : {0.0, 1e-4, 0.05, 0.3, 0.9, 1.0}) {
        for (double d : {0.0, 1e-3, 0.05, 0.4, 3.0}) {
            const double a = alpha * alpha, t = 2 * kDefaultSigma2 * d * d;
            const Sym2<double> r = filter_projected(Vec2<double>{a, a}, Vec2<double>{d, 0}, Vec2<double>{0, d},
                                                    kDefaultSigma2);
            EXPECT_NEAR(r.xx, filter_projected_isotropic(a, t), 1e-12) << alpha << " " << d;
            EXPECT_NEAR(r.yy, filter_projected_isotropic(a, t), 1e-12);
            EXPECT_NEAR(r.xy, 0.0, 1e-15);
            const Sym2<double> approx = filter_non_axis_aligned(Vec2<double>{a, a}, Vec2<double>{d, 0},
                                                                Vec2<double>{0, d}, kDefaultSigma2);
            EXPECT_NEAR(std::min(1.0, approx.xx), filter_approx_isotropic(a, t), 1e-12);
        }
    }
}

TEST(Methods, WorldNormalDifferenceIsProjectedDerivativeOfAverageNormal) {
    // TK21 Eq. (12): with n_hat = normalize(n + n'), |projection of n' - n onto the plane of n_hat| = |n - n'|.
    std::mt19937_64 rng(7);
    for (int k = 0; k < 200; ++k) {
        const Vec3<double> n = random_unit_upper(rng, -1.0);
        const Vec3<double> n2 = perturbed(rng, n, 0.3);
        const Vec3<double> m = normalize(n + n2);
        const Vec3<double> d = n2 - n;
        const double along = dot(d, m);
        EXPECT_NEAR(along, 0.0, 1e-12);  // the difference lies in the tangent plane of n_hat
        EXPECT_NEAR(std::sqrt(dot(d, d) - along * along), length(n - n2), 1e-12);
    }
}

TEST(Methods, EdgesPinned) {
    FilterInput<double> in;
    in.alpha = {0, 0};
    // Zero roughness, zero derivatives: nothing to filter (VAREF floors r at 0.04).
    for (const FilterMethod& m : filter_methods()) {
        const Sym2<double> r = evaluate(m, in);
        const double expected = m.name.starts_with("varef") ? std::pow(0.04, 4) : 0.0;
        EXPECT_NEAR(r.xx, expected, 1e-18) << m.name;
        EXPECT_NEAR(r.yy, expected, 1e-18) << m.name;
        EXPECT_EQ(r.xy, 0.0) << m.name;
    }
    // Fully rough stays fully rough for the saturating methods and for Listing 1.
    in.alpha = {1, 1};
    in.h = normalize(Vec3<double>{0.3, 0.1, 0.9});
    in.h_dx = normalize(Vec3<double>{0.35, 0.1, 0.9});
    in.h_dy = normalize(Vec3<double>{0.3, 0.2, 0.9});
    for (const char* name : {"slope-aa", "projected-aa", "projected", "iso-max", "iso-sum", "iso-mean"}) {
        const Sym2<double> r = evaluate_method(name, in).value();
        EXPECT_EQ(r.xx, 1.0) << name;
        EXPECT_EQ(r.yy, 1.0) << name;
        EXPECT_EQ(r.xy, 0.0) << name;
    }
    // One fully rough axis: Listing 1's limit keeps it at 1 and filters the other as a scalar.
    in.alpha = {1, 0.2};
    const Sym2<double> k = kernel_roughness(Vec2<double>{in.h_dx.x - in.h.x, in.h_dx.y - in.h.y},
                                            Vec2<double>{in.h_dy.x - in.h.x, in.h_dy.y - in.h.y}, in.sigma2);
    const double byy = 0.04 / 0.96 + k.yy;
    const Sym2<double> r = evaluate_method("projected", in).value();
    EXPECT_EQ(r.xx, 1.0);
    EXPECT_NEAR(r.yy, byy / (1 + byy), 1e-15);
    EXPECT_EQ(r.xy, 0.0);
    // Exactly grazing half vector: the slope-space kernel is unbounded.
    in.alpha = {0.1, 0.1};
    in.h = {1, 0, 0};
    in.h_dx = normalize(Vec3<double>{1, 0, 0.1});
    in.h_dy = normalize(Vec3<double>{1, 0.05, 0});
    const Sym2<double> s = evaluate_method("slope", in).value();
    EXPECT_EQ(s.xx, 1.0);
    EXPECT_EQ(s.yy, 1.0);
    const Sym2<double> saa = evaluate_method("slope-aa", in).value();
    EXPECT_NEAR(saa.xx, 0.01 + kDefaultKappa, 1e-15);
    EXPECT_NEAR(saa.yy, 0.01 + kDefaultKappa, 1e-15);
    // ... while the projected kernel stays small and finite there.
    const Sym2<double> p = evaluate_method("projected", in).value();
    EXPECT_LT(p.xx, 0.02);
    EXPECT_GE(p.xx, 0.01);
}

TEST(Methods, KappaClampAndItsDisabling) {
    FilterInput<double> in;
    in.alpha = {0.1, 0.1};
    in.h = {0, 0, 1};
    in.h_dx = normalize(Vec3<double>{1.5, 0, 1});  // large derivative: kernel 2 sigma^2 0.83^2 > kappa
    in.h_dy = in.h;
    in.n = {0, 0, 1};
    in.n_dx = in.h_dx;
    in.n_dy = in.n;
    EXPECT_NEAR(evaluate_method("projected-aa", in).value().xx, 0.01 + kDefaultKappa, 1e-15);
    in.kappa = std::numeric_limits<double>::infinity();
    const double dx = in.h_dx.x;
    EXPECT_NEAR(evaluate_method("projected-aa", in).value().xx, 0.01 + 2 * kDefaultSigma2 * dx * dx, 1e-15);
    const double dn2 = dot(in.n_dx - in.n, in.n_dx - in.n);
    EXPECT_NEAR(evaluate_method("iso-sum", in).value().xx, 0.01 + 2 * kDefaultSigma2 * dn2, 1e-15);
    EXPECT_NEAR(evaluate_method("iso-mean", in).value().xx, 0.01 + kDefaultSigma2 * dn2, 1e-15);
}

}  // namespace
}  // namespace specbake
