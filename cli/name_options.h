// CLI11 checks built from the name arrays kept beside the enums (core/enum_names.h), so an option accepts
// exactly the spellings the enum's parse_X does.
#pragma once

#include <CLI/CLI.hpp>

#include <array>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace specbake::cli {

template <size_t N>
CLI::IsMember is_member_of(const std::array<std::string_view, N>& names) {
    return CLI::IsMember(std::vector<std::string>(names.begin(), names.end()));
}

}  // namespace specbake::cli
