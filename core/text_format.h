// printf-style formatting of one number, for the tables and messages of the jobs.
#pragma once

#include <cstdio>
#include <string>

namespace specbake {

inline std::string format_double(const char* format, double value) {
    char buf[64];
    std::snprintf(buf, sizeof buf, format, value);
    return buf;
}

}  // namespace specbake
