// Fit of the node parameters of the include's closed-form convolved NDF (specaa_closed_form_nodes in
// shaders/src/specaa_body.inc, closed_form_nodes in bake/ggx.cpp). Not part of the build:
//   c++ -O2 -std=c++20 -o fit shaders/fit/convolved_ndf_fit.cpp
//   ./fit s -3 -0.25   # the set below z = log10(k / a) = -0.25 (kClosedFormSmall)
//   ./fit l -0.25 4    # the set above (kClosedFormLarge)
// Each prints, after every refinement, the 12 coefficients (c0..c3 of p1, then of q, then of p2); the last
// line is the set in the include; stderr shows the per-z fits and the largest relative error.
// The target is the isotropic convolution in GGX(a) units, pi a P(x) = int_0^inf e^-w w / (1 + b w)
// e^(-w x / (1 + b w)) w d(ln w) with x = tan^2(theta_h) / a, b = k / a, by a dense trapezoid rule in ln w.
// The model: the truncated mixture T(y) plus two Beckmann nodes with logit t_i = ln b + p_i (width
// a e^-p_i over the kernel), w1 = q b / (1 + b) (small set) or e^(-1/b) / (1 + e^-q) (large set),
// w2 = e^(-1/b) - w1. Per z: minimax fits of (p1, q, p2) by Nelder-Mead, continued from the previous z;
// then least-squares cubics in z; then Nelder-Mead on the 12 coefficients (L16, then minimax) over the range.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <vector>
constexpr int NC = 4, NP = 3 * NC;
using P = std::array<double, NP>;
double F(double x, double b) {
    double sum = 0;
    int n = 3000;
    double lo = -30, hi = std::log(60.0);
    double ds = (hi - lo) / n;
    for (int i = 0; i <= n; ++i) {
        double w = std::exp(lo + ds * i);
        double f = std::exp(-w) * w / (1 + b * w) * std::exp(-w * x / (1 + b * w)) * w;
        sum += (i == 0 || i == n ? 0.5 : 1) * f;
    }
    return sum * ds;
}
bool LARGE = false;
double modelp(double x, double b, double p0, double p1, double p2) {
    double y = x / b, L = y + 1 / b;
    double T = (L > 1e-3 ? (1 - std::exp(-L) * (1 + L)) / (L * L) : 0.5 - L / 3) / b;
    double e0 = b * std::exp(p0), e2 = b * std::exp(p2);
    double t1 = e0 / (1 + e0), t2 = e2 / (1 + e2);
    double w1 = LARGE ? std::exp(-1 / b) / (1 + std::exp(-p1)) : b / (1 + b) * p1, w2 = std::exp(-1 / b) - w1;
    return (T + w1 * t1 * std::exp(-y * t1) + w2 * t2 * std::exp(-y * t2)) / b;
}
// Nelder-Mead from p, the simplex's other points p + step along each axis (relative: step times
// max(0.05, |p_i|)); the best point after `iters` iterations.
template <int N>
std::array<double, N> nm(std::function<double(const std::array<double, N>&)> f, std::array<double, N> p, int iters,
                         double step, bool relative = true) {
    using Point = std::array<double, N>;
    std::array<Point, N + 1> s;
    std::array<double, N + 1> v;
    for (int i = 0; i <= N; ++i) {
        s[i] = p;
        if (i) s[i][i - 1] += relative ? step * std::max(0.05, std::abs(p[i - 1])) : step;
        v[i] = f(s[i]);
    }
    for (int it = 0; it < iters; ++it) {
        std::array<int, N + 1> o;
        for (int i = 0; i <= N; ++i) o[i] = i;
        std::sort(o.begin(), o.end(), [&](int a, int b) { return v[a] < v[b]; });
        auto S = s;
        auto V = v;
        for (int i = 0; i <= N; ++i) {
            s[i] = S[o[i]];
            v[i] = V[o[i]];
        }
        Point c{};
        for (int i = 0; i < N; ++i)
            for (int j = 0; j < N; ++j) c[j] += s[i][j] / N;
        auto pt = [&](double t) {
            Point r;
            for (int j = 0; j < N; ++j) r[j] = c[j] + t * (s[N][j] - c[j]);
            return r;
        };
        auto r = pt(-1);
        double fr = f(r);
        if (fr < v[0]) {
            auto e = pt(-2);
            double fe = f(e);
            if (fe < fr) {
                s[N] = e;
                v[N] = fe;
            } else {
                s[N] = r;
                v[N] = fr;
            }
        } else if (fr < v[N - 1]) {
            s[N] = r;
            v[N] = fr;
        } else {
            auto k = pt(0.5);
            double fk = f(k);
            if (fk < v[N]) {
                s[N] = k;
                v[N] = fk;
            } else {
                for (int i = 1; i <= N; ++i) {
                    for (int j = 0; j < N; ++j) s[i][j] = 0.5 * (s[i][j] + s[0][j]);
                    v[i] = f(s[i]);
                }
            }
        }
    }
    return s[std::min_element(v.begin(), v.end()) - v.begin()];
}
int main(int argc, char** argv) {
    bool small = argv[1][0] == 's';
    LARGE = !small;
    double lo = atof(argv[2]), hi = atof(argv[3]);
    std::vector<double> xs;
    for (double t = -4; t <= 7; t += 0.1) xs.push_back(std::pow(10.0, t));
    xs.push_back(0);
    std::vector<double> zs;
    for (double z = lo; z <= hi + 1e-9; z += 0.125) zs.push_back(z);
    std::vector<std::vector<double>> ex;
    for (double z : zs) {
        std::vector<double> r;
        for (double x : xs) r.push_back(F(x, std::pow(10.0, z)));
        ex.push_back(r);
    }
    // per-b with continuation
    std::vector<std::array<double, 3>> per(zs.size());
    std::array<double, 3> p =
        small ? std::array<double, 3>{1.8903, -0.3497, -0.8865} : std::array<double, 3>{-4.2636, 6.0, -11.3486};
    for (size_t n = 0; n < zs.size(); ++n) {
        size_t j = small ? n : zs.size() - 1 - n;
        double b = std::pow(10.0, zs[j]);
        auto f = [&](const std::array<double, 3>& q) {
            double m = 0;
            for (size_t i = 0; i < xs.size(); ++i) {
                double e = std::abs(modelp(xs[i], b, std::min(q[0], 8.0), q[1], q[2]) / ex[j][i] - 1);
                if (!(e == e)) e = 1e9;
                m = std::max(m, e);
            }
            return m;
        };
        for (int rep = 0; rep < 3; ++rep) p = nm<3>(f, p, 400, 0.2, false);
        p[0] = std::min(p[0], 8.0);
        p[1] = std::clamp(p[1], -12.0, 12.0);
        per[j] = p;
        fprintf(stderr, "z %.3f err %.4f p %.4f %.4f %.4f\n", zs[j], f(p), p[0], p[1], p[2]);
    }
    P coef{};
    for (int k = 0; k < 3; ++k) {
        double M[NC][NC + 1] = {};
        for (size_t j = 0; j < zs.size(); ++j) {
            double pw[NC];
            pw[0] = 1;
            for (int d = 1; d < NC; ++d) pw[d] = pw[d - 1] * zs[j];
            for (int r = 0; r < NC; ++r) {
                for (int c = 0; c < NC; ++c) M[r][c] += pw[r] * pw[c];
                M[r][NC] += pw[r] * per[j][k];
            }
        }
        for (int c = 0; c < NC; ++c) {
            int piv = c;
            for (int r = c + 1; r < NC; ++r)
                if (std::abs(M[r][c]) > std::abs(M[piv][c])) piv = r;
            for (int q = 0; q <= NC; ++q) std::swap(M[c][q], M[piv][q]);
            for (int r = 0; r < NC; ++r)
                if (r != c) {
                    double fct = M[r][c] / M[c][c];
                    for (int q = 0; q <= NC; ++q) M[r][q] -= fct * M[c][q];
                }
        }
        for (int c = 0; c < NC; ++c) coef[k * NC + c] = M[c][NC] / M[c][c];
    }
    auto poly = [&](const P& c, int k, double z) {
        double v = 0;
        for (int d = NC - 1; d >= 0; --d) v = v * z + c[k * NC + d];
        return v;
    };
    double PW = 1000;
    auto gerr = [&](const P& c) {
        double m = 0, sp = 0;
        int cnt = 0;
        for (size_t j = 0; j < zs.size(); ++j) {
            double b = std::pow(10.0, zs[j]);
            double p0 = poly(c, 0, zs[j]), p1 = poly(c, 1, zs[j]), p2 = poly(c, 2, zs[j]);
            for (size_t i = 0; i < xs.size(); ++i) {
                double e = std::abs(modelp(xs[i], b, p0, p1, p2) / ex[j][i] - 1);
                if (!(e == e)) e = 1e9;
                m = std::max(m, e);
                sp += std::pow(std::min(e, 10.0), PW > 100 ? 1 : PW);
                ++cnt;
            }
        }
        return PW > 100 ? m : std::pow(sp / cnt, 1 / PW);
    };
    fprintf(stderr, "lsq max %.4f\n", gerr(coef));
    for (int r = 0; r < 8; ++r) {
        PW = r < 3 ? 16 : 1000;
        coef = nm<NP>(gerr, coef, 2500, 0.05);
        double sv = PW;
        PW = 1000;
        fprintf(stderr, "refine %d %.4f\n", r, gerr(coef));
        PW = sv;
        for (double q : coef) printf("%.9g, ", q);
        printf("\n");
        fflush(stdout);
    }
}
