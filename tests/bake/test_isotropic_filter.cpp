// bake/isotropic_filter.h (SPEC Sec. 3) against the matrix form of TK21 Eq. (4)-(8), Eigen eigenvalues and
// its documented edges.
#include "bake/isotropic_filter.h"
#include "reference.h"

#include <gtest/gtest.h>

namespace specbake {
namespace {

TEST(IsotropicFilter, ProjectedClosedFormIsEq8ForIsotropicMatrices) {
    const Eigen::Matrix2d I = Eigen::Matrix2d::Identity();
    for (double a : {1e-6, 1e-3, 0.01, 0.2, 0.7, 0.99}) {
        for (double t : {0.0, 1e-5, 1e-2, 0.3, 5.0}) {
            const Eigen::Matrix2d A = a * I;
            const Eigen::Matrix2d Abar = (((A.inverse() - I).inverse() + t * I).inverse() + I).inverse();
            EXPECT_NEAR(filter_projected_isotropic(a, t), Abar(0, 0), 1e-12 * (1 + Abar(0, 0))) << a << " " << t;
            EXPECT_NEAR(filter_projected_isotropic(float(a), float(t)), Abar(0, 0), 1e-6) << a << " " << t;
        }
    }
}

TEST(IsotropicFilter, ProjectedEdgesAndMonotonicity) {
    EXPECT_EQ(filter_projected_isotropic(0.0, 0.0), 0.0);
    EXPECT_EQ(filter_projected_isotropic(1.0, 3.0), 1.0);
    EXPECT_EQ(filter_projected_isotropic(0.3, 0.0), 0.3);
    EXPECT_NEAR(filter_projected_isotropic(0.0, 1e12), 1.0, 1e-11);
    double previous = 0.0;
    for (double t = 0.0; t < 10.0; t += 0.01) {
        const double a = filter_projected_isotropic(0.05, t);
        EXPECT_GE(a, previous);
        EXPECT_GE(a, 0.05);
        EXPECT_LE(a, 1.0);
        previous = a;
    }
}

TEST(IsotropicFilter, ApproxIsEq9Saturated) {
    EXPECT_DOUBLE_EQ(filter_approx_isotropic(0.1, 0.2), 0.30000000000000004);
    EXPECT_EQ(filter_approx_isotropic(0.7, 0.5), 1.0);
    EXPECT_EQ(filter_approx_isotropic(0.0, 0.0), 0.0);
}

TEST(IsotropicFilter, ReductionsAgainstEigenvalues) {
    std::mt19937_64 rng(13);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int k = 0; k < 500; ++k) {
        const Eigen::Matrix2d S = test::random_psd(rng, u(rng), 1e-3 * u(rng));
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(S);
        const double l0 = eig.eigenvalues()(0), l1 = eig.eigenvalues()(1);
        const double xx = S(0, 0), yy = S(1, 1), xy = S(0, 1);
        EXPECT_NEAR(max_eigenvalue_sym2(xx, yy, xy), l1, 1e-12);
        EXPECT_NEAR(reduce_covariance(IsotropicReduction::Mean, xx, yy, xy), l0 + l1, 1e-12);
        EXPECT_NEAR(reduce_covariance(IsotropicReduction::Sum, xx, yy, xy), 2 * (l0 + l1), 1e-12);
        EXPECT_NEAR(reduce_covariance(IsotropicReduction::Max, xx, yy, xy), 2 * l1, 1e-12);
        // Conservative ordering of TK21 Sec. 5.3: 2 lambda_max <= 2 tr.
        EXPECT_LE(reduce_covariance(IsotropicReduction::Max, xx, yy, xy),
                  reduce_covariance(IsotropicReduction::Sum, xx, yy, xy) + 1e-15);
    }
}

}  // namespace
}  // namespace specbake
