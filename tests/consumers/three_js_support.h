// Which files three.js r187's loaders implement, from the file's header and the loaders' source
// (KTX2Loader's FORMAT_MAP, DDSLoader.parse's FourCC / bit-mask / DXGI cases): a supported file must load,
// any other is reported as the consumer's limitation with this reason.
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <set>
#include <string>

namespace specbake::consumers {

struct Support {
    bool supported = true;
    std::string reason;  // why not, when not
};

inline uint32_t le32(const std::string& b, size_t at) {
    uint32_t v = 0;
    if (at + 4 <= b.size()) std::memcpy(&v, b.data() + at, 4);
    return v;
}

inline Support loader_supports(const std::string& loader, const std::string& bytes) {
    if (loader == "KTX2Loader") {
        // KTX2Loader.js FORMAT_MAP (r187): 0 = Basis Universal; 8/16/32-bit R, RG, RGBA; RGBA16 UNORM;
        // E5B9G9R9, B10G11R11; BC1, BC3, BC4, BC5, BC7; ETC2/EAC; ASTC 4x4 and 6x6; PVRTC1.
        static const std::set<uint32_t> vk = {0,   9,   15,  16,  21,  37,  43,  76,  83,  91,  97,  100, 103,
                                              109, 122, 123, 131, 132, 133, 134, 137, 138, 139, 140, 141, 142,
                                              145, 146, 148, 152, 153, 154, 155, 156, 157, 158, 165, 166,
                                              1000054000, 1000054001, 1000054004, 1000054005,
                                              1000066000, 1000066004};
        const uint32_t format = le32(bytes, 12);
        if (vk.count(format)) return {};
        return {false, "KTX2Loader has no vkFormat " + std::to_string(format)};
    }
    if (loader == "DDSLoader") {
        // DDSLoader.parse: FourCC DXT1, DXT3, DXT5, ETC1; DX10 with BC6H only; else 32-bit A8R8G8B8 or
        // 24-bit R8G8B8 masks (red in 0x00ff0000).
        const std::string fourcc = bytes.size() >= 88 ? bytes.substr(84, 4) : "";
        if (fourcc == "DXT1" || fourcc == "DXT3" || fourcc == "DXT5" || fourcc == "ETC1") return {};
        if (fourcc == "DX10") {
            const uint32_t dxgi = le32(bytes, 128);
            if (dxgi == 95 || dxgi == 96) return {};
            return {false, "DDSLoader reads DX10 files only as BC6H, not DXGI format " + std::to_string(dxgi)};
        }
        const uint32_t bits = le32(bytes, 88), r = le32(bytes, 92), g = le32(bytes, 96), b = le32(bytes, 100),
                       a = le32(bytes, 104);
        if (bits == 32 && (r & 0xff0000) && (g & 0xff00) && (b & 0xff) && (a & 0xff000000u)) return {};
        if (bits == 24 && (r & 0xff0000) && (g & 0xff00) && (b & 0xff)) return {};
        if (fourcc[0] != '\0' && le32(bytes, 84) > 0xff)
            return {false, "DDSLoader has no FourCC " + fourcc};
        if (le32(bytes, 84) != 0) return {false, "DDSLoader has no FourCC " + std::to_string(le32(bytes, 84))};
        return {false, "DDSLoader reads uncompressed data only as A8R8G8B8 / R8G8B8 (" + std::to_string(bits) +
                           "-bit, red mask 0x" + [&] { char s[16]; std::snprintf(s, sizeof s, "%x", r); return std::string(s); }() + ")"};
    }
    return {};  // EXRLoader (R, G, B [A] or Y channels) and TextureLoader (PNG) read every specbake output
}

}  // namespace specbake::consumers
