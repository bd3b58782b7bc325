// PCG32 (O'Neill 2014, "PCG: A Family of Simple Fast Space-Efficient Statistically Good Algorithms for
// Random Number Generation", pcg32_srandom_r / pcg32_random_r): the project's seeded generator.
#pragma once

#include <cstdint>

namespace specbake {

class Pcg32 {
public:
    // pcg32_srandom_r(seed, stream): independent sequences per stream.
    Pcg32(uint64_t seed, uint64_t stream) : inc_((stream << 1u) | 1u) {
        next();
        state_ += seed;
        next();
    }
    uint32_t next() {
        const uint64_t old = state_;
        state_ = old * 6364136223846793005ULL + inc_;
        const uint32_t xorshifted = uint32_t(((old >> 18u) ^ old) >> 27u);
        const uint32_t rot = uint32_t(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
    }
    // Uniform in [0, 1) with 53 random bits (27 from one draw, 26 from the next).
    double uniform() {
        const uint64_t hi = next() >> 5, lo = next() >> 6;
        return double((hi << 26) | lo) * (1.0 / 9007199254740992.0);
    }

private:
    uint64_t state_ = 0;
    uint64_t inc_;
};

}  // namespace specbake
