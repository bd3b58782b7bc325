// Name <-> enum through one array of names in enum order, kept beside each enum (core/image.h WrapMode,
// bake/texture_bake.h, ...), so the command line, config files and manifests spell a value one way.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string_view>

namespace specbake {

// The enumerator named `name` in `names` (listed in enum order, enumerators 0, 1, ...), if any.
template <class E, size_t N>
constexpr std::optional<E> enum_from_name(const std::array<std::string_view, N>& names, std::string_view name) {
    for (size_t i = 0; i < N; ++i)
        if (names[i] == name) return E(i);
    return std::nullopt;
}

}  // namespace specbake
