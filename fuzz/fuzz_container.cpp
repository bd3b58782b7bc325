// libFuzzer target: the KTX2 and DDS readers of `inspect` (io/texture/container_inspect.h): the structural check
// of both containers, then the decoder for whatever the check accepts, as `inspect` runs them.
#include "io/texture/container_inspect.h"

#include <cstring>

namespace {

void check_decoded(const specbake::io::InspectedTexture& t) {
    for (const specbake::Image& level : t.mips.levels)
        if (level.pixels.size() != size_t(level.width) * level.height * level.channels) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::span<const uint8_t> bytes{data, size};
    // Both checks see every input: each must refuse the other's files and noise with an error.
    const bool ktx2 = bool(specbake::io::check_ktx2_structure(bytes, "fuzz.ktx2"));
    const bool dds = bool(specbake::io::check_dds_structure(bytes, "fuzz.dds"));
    if (ktx2 && dds) __builtin_trap();  // no file is both
    if (ktx2) {
        auto t = specbake::io::decode_ktx2_for_inspection(bytes, "fuzz.ktx2");
        if (t) check_decoded(*t);
    }
    if (dds) {
        auto t = specbake::io::decode_dds_for_inspection(bytes, "fuzz.dds");
        if (t) check_decoded(*t);
    }
    return 0;
}
