// Allocator settings of the specbake executable (and of the benchmarks, which measure what it runs). It is
// linked with jemalloc where that is installed, and jemalloc reads this symbol at start-up: transparent
// huge pages for all of its memory. A scene bake fills a few hundred MB of fresh memory; faulted in 2 MB
// at a time instead of 4 KB it takes some 20k fewer page faults and ~10% less time for a 1M-triangle
// mesh here (bench/bench_scene.cpp). The C library's allocator ignores the symbol.
extern "C" {
extern const char* malloc_conf;
const char* malloc_conf = "thp:always,metadata_thp:auto";
}
