#include "io/files/sha256.h"

#include "io/files/file_read.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <cpuid.h>
#include <immintrin.h>
#define SPECBAKE_SHA_NI 1
#endif

namespace specbake::io {
namespace {

alignas(16) constexpr uint32_t kRoundConstants[64] = {
    0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5,
    0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174,
    0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da,
    0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967,
    0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85,
    0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070,
    0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
    0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7, 0xc67178f2};

constexpr std::array<uint32_t, 8> kInitialState = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                                                   0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};

using CompressFn = void (*)(uint32_t* state, const uint8_t* blocks, size_t block_count);

inline uint32_t rotr(uint32_t x, int n) { return (x >> n) | (x << (32 - n)); }
inline uint32_t load_be32(const uint8_t* p) {
    return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | uint32_t(p[3]);
}

// FIPS 180-4 Sec. 6.2.2, with the message schedule kept in a 16-word ring instead of 64 words.
void compress_portable(uint32_t* state, const uint8_t* blocks, size_t block_count) {
    for (; block_count > 0; --block_count, blocks += 64) {
        uint32_t w[16];
        for (int i = 0; i < 16; ++i) w[i] = load_be32(blocks + 4 * i);
        uint32_t a = state[0], b = state[1], c = state[2], d = state[3];
        uint32_t e = state[4], f = state[5], g = state[6], h = state[7];
        for (int i = 0; i < 64; ++i) {
            if (i >= 16) {
                const uint32_t w15 = w[(i - 15) & 15], w2 = w[(i - 2) & 15];
                const uint32_t s0 = rotr(w15, 7) ^ rotr(w15, 18) ^ (w15 >> 3);
                const uint32_t s1 = rotr(w2, 17) ^ rotr(w2, 19) ^ (w2 >> 10);
                w[i & 15] += s0 + w[(i - 7) & 15] + s1;
            }
            const uint32_t t1 = h + (rotr(e, 6) ^ rotr(e, 11) ^ rotr(e, 25)) + ((e & f) ^ (~e & g)) +
                                kRoundConstants[i] + w[i & 15];
            const uint32_t t2 = (rotr(a, 2) ^ rotr(a, 13) ^ rotr(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
            h = g;
            g = f;
            f = e;
            e = d + t1;
            d = c;
            c = b;
            b = a;
            a = t1 + t2;
        }
        state[0] += a;
        state[1] += b;
        state[2] += c;
        state[3] += d;
        state[4] += e;
        state[5] += f;
        state[6] += g;
        state[7] += h;
    }
}

#ifdef SPECBAKE_SHA_NI
// The same compression with the x86 SHA extensions (Intel, "New Instructions Supporting the Secure Hash
// Algorithm on Intel Architecture Processors", 2013): sha256rnds2 does two rounds on the state held as
// (A,B,E,F) and (C,D,G,H); sha256msg1/msg2 extend the message schedule four words at a time. `Lanes`
// independent messages go through the rounds interleaved: each pair of rounds depends on the one before,
// so one message alone leaves the unit idle for most of each instruction's latency, which the other
// messages' rounds fill.
template <int Lanes>
__attribute__((target("sha,sse4.1,ssse3"))) void compress_sha_ni_lanes(uint32_t* const* states,
                                                                        const uint8_t* const* blocks,
                                                                        size_t block_count) {
    const __m128i byte_swap = _mm_set_epi64x(0x0c0d0e0f08090a0bULL, 0x0405060700010203ULL);
    __m128i abef[Lanes], cdgh[Lanes];
    for (int l = 0; l < Lanes; ++l) {
        const __m128i dcba = _mm_loadu_si128(reinterpret_cast<const __m128i*>(states[l]));
        const __m128i hgfe = _mm_loadu_si128(reinterpret_cast<const __m128i*>(states[l] + 4));
        const __m128i cdab = _mm_shuffle_epi32(dcba, 0xB1);
        const __m128i efgh = _mm_shuffle_epi32(hgfe, 0x1B);
        abef[l] = _mm_alignr_epi8(cdab, efgh, 8);
        cdgh[l] = _mm_blend_epi16(efgh, cdab, 0xF0);
    }
    for (size_t b = 0; b < block_count; ++b) {
        __m128i abef_before[Lanes], cdgh_before[Lanes], w[Lanes][4];
        for (int l = 0; l < Lanes; ++l) abef_before[l] = abef[l], cdgh_before[l] = cdgh[l];
#pragma GCC unroll 16
        for (int group = 0; group < 16; ++group) {
            const __m128i round_constants = _mm_load_si128(reinterpret_cast<const __m128i*>(kRoundConstants + 4 * group));
#pragma GCC unroll 3
            for (int l = 0; l < Lanes; ++l) {
                __m128i& cur = w[l][group & 3];
                if (group < 4) {
                    cur = _mm_shuffle_epi8(
                        _mm_loadu_si128(reinterpret_cast<const __m128i*>(blocks[l] + 64 * b + 16 * group)), byte_swap);
                } else {
                    // W[t] = sigma1(W[t-2]) + W[t-7] + sigma0(W[t-15]) + W[t-16], four words at once.
                    const __m128i& prev1 = w[l][(group - 1) & 3];
                    const __m128i& prev2 = w[l][(group - 2) & 3];
                    const __m128i& prev3 = w[l][(group - 3) & 3];
                    __m128i t = _mm_sha256msg1_epu32(cur, prev3);
                    t = _mm_add_epi32(t, _mm_alignr_epi8(prev1, prev2, 4));
                    cur = _mm_sha256msg2_epu32(t, prev1);
                }
                __m128i k = _mm_add_epi32(cur, round_constants);
                cdgh[l] = _mm_sha256rnds2_epu32(cdgh[l], abef[l], k);
                k = _mm_shuffle_epi32(k, 0x0E);
                abef[l] = _mm_sha256rnds2_epu32(abef[l], cdgh[l], k);
            }
        }
        for (int l = 0; l < Lanes; ++l) {
            abef[l] = _mm_add_epi32(abef[l], abef_before[l]);
            cdgh[l] = _mm_add_epi32(cdgh[l], cdgh_before[l]);
        }
    }
    for (int l = 0; l < Lanes; ++l) {
        const __m128i feba = _mm_shuffle_epi32(abef[l], 0x1B);
        const __m128i dchg = _mm_shuffle_epi32(cdgh[l], 0xB1);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(states[l]), _mm_blend_epi16(feba, dchg, 0xF0));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(states[l] + 4), _mm_alignr_epi8(dchg, feba, 8));
    }
}

void compress_sha_ni(uint32_t* state, const uint8_t* blocks, size_t block_count) {
    compress_sha_ni_lanes<1>(&state, &blocks, block_count);
}

bool cpu_has_sha_ni() {
    unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
    if (!__get_cpuid(1, &eax, &ebx, &ecx, &edx)) return false;
    const bool ssse3 = ecx & (1u << 9), sse41 = ecx & (1u << 19);
    if (!__get_cpuid_count(7, 0, &eax, &ebx, &ecx, &edx)) return false;
    const bool sha = ebx & (1u << 29);
    return ssse3 && sse41 && sha;
}
#endif

CompressFn best_compress() {
#ifdef SPECBAKE_SHA_NI
    static const CompressFn chosen = cpu_has_sha_ni() ? &compress_sha_ni : &compress_portable;
    return chosen;
#else
    return &compress_portable;
#endif
}

// Compresses `block_count` blocks of each of `lanes` (1 to 3) independent messages.
void compress_lanes(uint32_t* const* states, const uint8_t* const* blocks, int lanes, size_t block_count) {
#ifdef SPECBAKE_SHA_NI
    if (best_compress() == &compress_sha_ni) {
        if (lanes == 3) return compress_sha_ni_lanes<3>(states, blocks, block_count);
        if (lanes == 2) return compress_sha_ni_lanes<2>(states, blocks, block_count);
        return compress_sha_ni_lanes<1>(states, blocks, block_count);
    }
#endif
    for (int l = 0; l < lanes; ++l) compress_portable(states[l], blocks[l], block_count);
}

// Buffering and padding (FIPS 180-4 Sec. 5.1.1) around one compression function.
class Hasher {
public:
    explicit Hasher(CompressFn compress) : compress_(compress) {}

    void update(const uint8_t* bytes, size_t size, std::array<uint32_t, 8>& h, std::array<uint8_t, 64>& buffer,
                size_t& buffered, uint64_t& total) const {
        total += size;
        if (buffered > 0) {
            const size_t take = std::min(size, 64 - buffered);
            std::memcpy(buffer.data() + buffered, bytes, take);
            buffered += take;
            bytes += take;
            size -= take;
            if (buffered < 64) return;
            compress_(h.data(), buffer.data(), 1);
            buffered = 0;
        }
        const size_t blocks = size / 64;
        if (blocks > 0) compress_(h.data(), bytes, blocks);
        buffered = size - blocks * 64;
        if (buffered > 0) std::memcpy(buffer.data(), bytes + blocks * 64, buffered);
    }

    std::string finish(std::array<uint32_t, 8>& h, std::array<uint8_t, 64>& buffer, size_t buffered,
                       uint64_t total) const {
        const uint64_t bits = total * 8;
        uint8_t tail[128] = {};
        std::memcpy(tail, buffer.data(), buffered);
        tail[buffered] = 0x80;
        const size_t tail_size = buffered + 1 + 8 <= 64 ? 64 : 128;
        for (int i = 0; i < 8; ++i) tail[tail_size - 1 - size_t(i)] = uint8_t(bits >> (8 * i));
        compress_(h.data(), tail, tail_size / 64);
        static const char* digits = "0123456789abcdef";
        std::string out;
        out.reserve(64);
        for (uint32_t word : h)
            for (int shift = 28; shift >= 0; shift -= 4) out.push_back(digits[(word >> shift) & 0xf]);
        return out;
    }

private:
    CompressFn compress_;
};

std::string hash_with(CompressFn compress, std::span<const uint8_t> bytes) {
    std::array<uint32_t, 8> h = kInitialState;
    std::array<uint8_t, 64> buffer{};
    size_t buffered = 0;
    uint64_t total = 0;
    const Hasher hasher(compress);
    hasher.update(bytes.data(), bytes.size(), h, buffer, buffered, total);
    return hasher.finish(h, buffer, buffered, total);
}

// How many workers hash ranges: one per core that is idle (the 1-minute load average against the cores
// TBB may use), at least one. On a busy machine every extra worker costs CPU time, since its ranges are
// hashed in fewer lanes than one worker would interleave them in: on a 1.52 GB bake with two cores at a
// load of 4, one worker took 0.88 CPU s and 2.7 s, two took 1.04 CPU s and 3.2 s; with the cores free, two
// finish first (the longest range alone bounds them).
size_t hashing_workers() {
    const int cores = tbb::this_task_arena::max_concurrency();
    double load[1] = {0.0};
    if (::getloadavg(load, 1) != 1) return size_t(std::max(1, cores));
    return size_t(std::clamp(int(double(cores) - load[0] + 0.5), 1, std::max(1, cores)));
}

}  // namespace

Sha256::Sha256() : h_(kInitialState) {}

void Sha256::update(std::span<const uint8_t> bytes) {
    Hasher(best_compress()).update(bytes.data(), bytes.size(), h_, buffer_, buffered_, total_bytes_);
}

void Sha256::update(const std::string& text) {
    update(std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
}

std::string Sha256::hex() { return Hasher(best_compress()).finish(h_, buffer_, buffered_, total_bytes_); }

std::string sha256_hex(std::span<const uint8_t> bytes) { return hash_with(best_compress(), bytes); }

std::string sha256_hex_portable(std::span<const uint8_t> bytes) { return hash_with(&compress_portable, bytes); }

bool sha256_uses_cpu_extensions() { return best_compress() != &compress_portable; }

Result<std::string> sha256_file(const std::filesystem::path& path) {
    // Hashed from a read-only mapping (no copy out of the page cache), in windows whose pages are dropped
    // from the mapping once hashed, so a multi-GB file costs a few MB of memory.
    auto file = MappedFile::open(path);
    if (!file) return make_error(file.error().message + " (while hashing)");
    const std::span<const uint8_t> bytes = file->bytes();
    constexpr size_t kWindow = size_t(4) << 20;
    Sha256 s;
    for (size_t at = 0; at < bytes.size(); at += kWindow) {
        const size_t n = std::min(kWindow, bytes.size() - at);
        s.update(bytes.subspan(at, n));
        file->release_pages(at, n);
    }
    return s.hex();
}

std::vector<std::string> sha256_ranges(std::span<const std::span<const uint8_t>> ranges, const HashWindowFn& before,
                                       const HashWindowFn& after) {
    constexpr int kLanes = 3;
    constexpr size_t kWindowBlocks = (size_t(4) << 20) / 64;
    // Longest first, each to the worker holding the fewest bytes so far (LPT scheduling).
    std::vector<size_t> order(ranges.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return ranges[a].size() > ranges[b].size(); });
    const size_t workers = std::min(hashing_workers(), std::max<size_t>(1, ranges.size()));
    std::vector<std::vector<size_t>> share(workers);
    std::vector<uint64_t> load(workers, 0);
    for (size_t i : order) {
        const size_t w = size_t(std::min_element(load.begin(), load.end()) - load.begin());
        share[w].push_back(i);
        load[w] += ranges[i].size();
    }
    std::vector<std::string> digests(ranges.size());
    tbb::parallel_for(size_t(0), workers, [&](size_t worker) {
        struct Lane {
            size_t range = 0, offset = 0;
            std::array<uint32_t, 8> h = kInitialState;
        };
        std::array<Lane, kLanes> lanes;
        int active = 0;
        size_t next = 0;
        const std::vector<size_t>& mine = share[worker];
        const Hasher hasher(best_compress());
        while (true) {
            while (active < kLanes && next < mine.size()) lanes[active++] = Lane{mine[next++], 0, kInitialState};
            if (active == 0) break;
            // A range with less than a block left is padded and finished; the others go on in lockstep.
            size_t step = kWindowBlocks;
            for (int l = 0; l < active;) {
                const std::span<const uint8_t> r = ranges[lanes[l].range];
                const size_t full = (r.size() - lanes[l].offset) / 64;
                if (full > 0) {
                    step = std::min(step, full);
                    ++l;
                    continue;
                }
                std::array<uint8_t, 64> tail{};
                const size_t rest = r.size() - lanes[l].offset;
                if (rest > 0) {
                    if (before) before(lanes[l].range, lanes[l].offset, rest);
                    std::memcpy(tail.data(), r.data() + lanes[l].offset, rest);
                    if (after) after(lanes[l].range, lanes[l].offset, rest);
                }
                digests[lanes[l].range] = hasher.finish(lanes[l].h, tail, rest, r.size());
                lanes[l] = lanes[--active];
            }
            if (active == 0) continue;
            uint32_t* states[kLanes];
            const uint8_t* blocks[kLanes];
            for (int l = 0; l < active; ++l) {
                if (before) before(lanes[l].range, lanes[l].offset, 64 * step);
                states[l] = lanes[l].h.data();
                blocks[l] = ranges[lanes[l].range].data() + lanes[l].offset;
            }
            compress_lanes(states, blocks, active, step);
            for (int l = 0; l < active; ++l) {
                if (after) after(lanes[l].range, lanes[l].offset, 64 * step);
                lanes[l].offset += 64 * step;
            }
        }
    });
    return digests;
}

Result<std::vector<std::string>> sha256_files(std::span<const std::filesystem::path> paths) {
    std::vector<Result<std::string>> results(paths.size(), Result<std::string>(std::string()));
    tbb::parallel_for(size_t(0), paths.size(), [&](size_t i) { results[i] = sha256_file(paths[i]); });
    std::vector<std::string> out;
    out.reserve(paths.size());
    for (auto& r : results) {
        if (!r) return r.error();
        out.push_back(std::move(*r));
    }
    return out;
}

}  // namespace specbake::io
