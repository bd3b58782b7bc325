// Four-lane double arithmetic for the mesh passes that are compiled twice, for AVX2 and for the baseline
// instruction set, and chosen once at load time (GCC/Clang function multiversioning: SPECBAKE_AVX2_CLONES
// on the pass, SPECBAKE_INLINE on its helpers so they are compiled into each version). Include it only from
// those .cpp files: it also turns off floating-point contraction for the rest of the translation unit.
#pragma once

#include <cmath>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

// Compilers may fuse multiplies and adds (GCC does in C++ even in ISO mode), and a fused operation rounds once
// where the baseline version rounds twice: off, so every version computes the same bits.
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#else
#pragma GCC optimize("fp-contract=off")
#endif

// Clang refuses a call passing a 32-byte vector between an AVX2 clone and a baseline helper even when the
// helper is always inlined (an ABI error, not GCC's note), so clang builds keep only the baseline version.
#if defined(__x86_64__) && defined(__linux__) && !defined(__clang__)
#define SPECBAKE_AVX2_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define SPECBAKE_AVX2_CLONES
#endif
#define SPECBAKE_INLINE __attribute__((always_inline)) inline

// Four doubles processed as one (GCC/Clang vector extension): one AVX2 register, two SSE2 registers. The
// helpers taking or returning them are always inlined, so the ABI note GCC gives for them does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace specbake::lanes {

typedef double v4d __attribute__((vector_size(32)));
typedef long v4l __attribute__((vector_size(32)));  // lane masks, as v4d comparisons yield
constexpr int kLanes = 4;

SPECBAKE_INLINE v4d splat(double x) { return v4d{x, x, x, x}; }

// Lane-wise square root (non-negative input): two SSE2 square roots where available.
SPECBAKE_INLINE v4d sqrt4(v4d x) {
#if defined(__SSE2__)
    const __m128d lo = _mm_sqrt_pd(__m128d{x[0], x[1]}), hi = _mm_sqrt_pd(__m128d{x[2], x[3]});
    return v4d{lo[0], lo[1], hi[0], hi[1]};
#else
    return v4d{std::sqrt(x[0]), std::sqrt(x[1]), std::sqrt(x[2]), std::sqrt(x[3])};
#endif
}

// Dot product of two lane-wise 3-vectors, summed x, y, z in that order.
SPECBAKE_INLINE v4d dot4(const v4d (&a)[3], const v4d (&b)[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

}  // namespace specbake::lanes
