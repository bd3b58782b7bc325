// SPECBAKE_ASSERT(cond): checks an internal invariant whose violation would silently corrupt output (an index
// out of range, a wrong level count, an asymmetric matrix, a buffer of the wrong size before a write).
// Active when SPECBAKE_ASSERTIONS is defined (the CMake option of that name; on in the sanitizer build),
// where a violation prints the condition and its place and aborts; otherwise the condition is not
// evaluated and the check costs nothing. Not for input validation: bad input is an error value (Result).
#pragma once

#if defined(SPECBAKE_ASSERTIONS)
#include <cstdio>
#include <cstdlib>

namespace specbake::detail {
[[noreturn]] inline void assertion_failed(const char* condition, const char* file, int line) {
    std::fprintf(stderr, "%s:%d: internal invariant violated: %s\n", file, line, condition);
    std::abort();
}
}  // namespace specbake::detail

#define SPECBAKE_ASSERT(cond) ((cond) ? void(0) : ::specbake::detail::assertion_failed(#cond, __FILE__, __LINE__))
#else
#define SPECBAKE_ASSERT(cond) ((void)sizeof(!(cond)))
#endif
