// Reading one-level UASTC KTX2 files and assembling a mip chain of UASTC levels into one KTX2 file
// (KTX 2.0 Sec. 3: header, index, level index, DFD, key/value data, levels smallest first).
#include "io/texture/ktx2_uastc.h"

#include "io/texture/byte_order.h"

#include <zstd.h>

#include <cstring>

namespace specbake::io {
namespace {

constexpr uint32_t kModelUastc = 166;  // KHR_DF_MODEL_UASTC

}  // namespace

size_t uastc_level_bytes(int w, int h) { return size_t((w + 3) / 4) * size_t((h + 3) / 4) * 16; }

Result<UastcFile> read_uastc_ktx2(std::span<const uint8_t> b, const std::string& name) {
    if (b.size() < 104 || std::memcmp(b.data(), kKtx2Identifier, 12) != 0) return make_error(name + ": not a KTX2 file");
    if (get32(b, 12) != 0) return make_error(name + ": vkFormat " + std::to_string(get32(b, 12)) + ", expected 0 (UASTC)");
    if (get32(b, 44) != 0) return make_error(name + ": supercompressed; expected plain UASTC levels");
    UastcFile f;
    f.level.width = int(get32(b, 20));
    f.level.height = int(get32(b, 24));
    const uint32_t dfd_offset = get32(b, 48), dfd_length = get32(b, 52);
    if (dfd_offset + uint64_t(dfd_length) > b.size() || dfd_length < 28)
        return make_error(name + ": data format descriptor out of the file");
    f.dfd.assign(b.begin() + dfd_offset, b.begin() + dfd_offset + dfd_length);
    // Basic descriptor block: colorModel is byte 4 of the block, after dfdTotalSize (4 bytes).
    if (f.dfd[4 + 8] != kModelUastc) return make_error(name + ": descriptor colour model is not UASTC");
    const uint64_t offset = get64(b, 80), length = get64(b, 88);
    if (offset + length > b.size()) return make_error(name + ": level 0 out of the file");
    if (length != uastc_level_bytes(f.level.width, f.level.height))
        return make_error(name + ": level 0 holds " + std::to_string(length) + " bytes, expected " +
                          std::to_string(uastc_level_bytes(f.level.width, f.level.height)));
    f.level.blocks.assign(b.begin() + offset, b.begin() + offset + length);
    return f;
}

std::vector<uint8_t> assemble_uastc_ktx2(const std::vector<UastcLevel>& levels, std::span<const uint8_t> dfd,
                                         const std::string& writer, int zstd_level) {
    const size_t n = levels.size();
    // The stored bytes of every level: the blocks, or one zstd frame of them.
    std::vector<std::vector<uint8_t>> stored(n);
    if (zstd_level > 0)
        for (size_t i = 0; i < n; ++i) {
            stored[i].resize(ZSTD_compressBound(levels[i].blocks.size()));
            const size_t z = ZSTD_compress(stored[i].data(), stored[i].size(), levels[i].blocks.data(),
                                           levels[i].blocks.size(), zstd_level);
            if (ZSTD_isError(z)) {  // only on a bad level or out of memory: keep the file plain instead
                zstd_level = 0;
                break;
            }
            stored[i].resize(z);
        }
    if (zstd_level <= 0)
        for (size_t i = 0; i < n; ++i) stored[i] = levels[i].blocks;
    const size_t alignment = zstd_level > 0 ? 1 : 16;
    const size_t index_end = 80 + 24 * n;
    const size_t dfd_offset = index_end;
    std::vector<uint8_t> kvd;
    {
        const std::string key = "KTXwriter";
        const uint32_t length = uint32_t(key.size() + 1 + writer.size() + 1);
        kvd.resize(4);
        std::memcpy(kvd.data(), &length, 4);
        kvd.insert(kvd.end(), key.begin(), key.end());
        kvd.push_back(0);
        kvd.insert(kvd.end(), writer.begin(), writer.end());
        kvd.push_back(0);
        while (kvd.size() % 4) kvd.push_back(0);
    }
    const size_t kvd_offset = dfd_offset + dfd.size();
    size_t end = kvd_offset + kvd.size();
    std::vector<size_t> offsets(n);
    for (size_t i = n; i-- > 0;) {  // smallest level first
        end = (end + alignment - 1) / alignment * alignment;
        offsets[i] = end;
        end += stored[i].size();
    }
    std::vector<uint8_t> f(end, 0);
    std::memcpy(f.data(), kKtx2Identifier, 12);
    put32(f, 12, 0);  // vkFormat: VK_FORMAT_UNDEFINED, the descriptor says UASTC
    put32(f, 16, 1);  // typeSize
    put32(f, 20, uint32_t(levels.front().width));
    put32(f, 24, uint32_t(levels.front().height));
    put32(f, 28, 0);  // pixelDepth
    put32(f, 32, 0);  // layerCount
    put32(f, 36, 1);  // faceCount
    put32(f, 40, uint32_t(n));
    put32(f, 44, zstd_level > 0 ? 2 : 0);  // supercompressionScheme: Zstandard or none
    put32(f, 48, uint32_t(dfd_offset));
    put32(f, 52, uint32_t(dfd.size()));
    put32(f, 56, uint32_t(kvd_offset));
    put32(f, 60, uint32_t(kvd.size()));
    put64(f, 64, 0);  // no supercompression global data
    put64(f, 72, 0);
    for (size_t i = 0; i < n; ++i) {
        put64(f, 80 + 24 * i, offsets[i]);
        put64(f, 88 + 24 * i, stored[i].size());
        put64(f, 96 + 24 * i, levels[i].blocks.size());
        std::memcpy(f.data() + offsets[i], stored[i].data(), stored[i].size());
    }
    std::memcpy(f.data() + dfd_offset, dfd.data(), dfd.size());
    std::memcpy(f.data() + kvd_offset, kvd.data(), kvd.size());
    return f;
}

}  // namespace specbake::io
