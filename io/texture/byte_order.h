// Little-endian field access for the container formats (KTX2, DDS; both are little-endian by definition)
// and the KTX2 file identifier (KTX 2.0 Sec. 3.1), shared by their writers and readers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

namespace specbake::io {

// The 12 bytes every KTX2 file starts with.
inline constexpr uint8_t kKtx2Identifier[12] = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n'};

// memcpy is the host's byte order; every supported host is little-endian (x86-64, AArch64).
inline uint32_t get32(std::span<const uint8_t> b, size_t at) {
    uint32_t v;
    std::memcpy(&v, b.data() + at, 4);
    return v;
}
inline uint64_t get64(std::span<const uint8_t> b, size_t at) {
    uint64_t v;
    std::memcpy(&v, b.data() + at, 8);
    return v;
}
inline void put32(std::vector<uint8_t>& b, size_t at, uint32_t v) { std::memcpy(b.data() + at, &v, 4); }
inline void put64(std::vector<uint8_t>& b, size_t at, uint64_t v) { std::memcpy(b.data() + at, &v, 8); }

}  // namespace specbake::io
