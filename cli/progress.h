// The progress display of long work (bake of many assets, texture of a large map, verify, bench): one line
// redrawn on a terminal, plain lines when stderr is not a terminal, nothing with --quiet.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>

namespace specbake {

struct RunSettings;

enum class ProgressMode {
    off,    // --quiet: nothing (errors are printed by their callers)
    lines,  // stderr is a file or pipe: one plain line per finished item
    bar,    // stderr is a terminal: one line, redrawn in place
};

// off with --quiet, bar when stderr is a terminal (RunSettings::progress_bar), else lines.
ProgressMode progress_mode(const RunSettings& settings);

// Prints one line on `stream` (stderr or stdout) with the output lock held: a progress bar on the
// terminal is cleared first and drawn again after, so lines from parallel work never interleave with it.
void print_line(std::FILE* stream, const std::string& line);

// Progress of `total` items ("assets", "frames", "scenes"). Thread-safe: parallel workers call
// finished() and status() concurrently. The line shows done/total, the current file and activity,
// elapsed time and, once something is done, the time remaining extrapolated from the rate so far:
//
//   [=========>          ] 12/40 assets  Helmet.gltf: writing textures  0:05 elapsed, ~0:12 left
//
// In lines mode either the activity lines are printed ("specbake: <activity>": the default for a single
// item, and for commands whose activity lines already count) or one line per finished item
// ("[12/40] done Helmet.gltf (5.1 s elapsed, ~12 s left)").
class ProgressDisplay {
public:
    enum class Lines { automatic, activity, finished };
    ProgressDisplay(size_t total, ProgressMode mode, std::string unit, Lines lines = Lines::automatic);
    ~ProgressDisplay();
    ProgressDisplay(const ProgressDisplay&) = delete;
    ProgressDisplay& operator=(const ProgressDisplay&) = delete;

    // What is being worked on now, e.g. "Helmet.gltf: writing textures of material 2".
    void status(const std::string& item, const std::string& activity);
    // Fraction [0, 1] of the item in work, for a single long item (rows of a large texture bake).
    void fraction(double done);
    // One item finished; `word` says how ("done", "up to date", "FAILED").
    void finished(const std::string& item, const char* word);
    // Clears the line (the destructor does it too).
    void close();

    ProgressMode mode() const { return mode_; }
    size_t count() const;

private:
    friend void print_line(std::FILE* stream, const std::string& line);
    void draw_locked(bool force);
    double elapsed() const;
    std::string timing(bool long_form) const;

    size_t total_;
    ProgressMode mode_;
    std::string unit_;
    std::chrono::steady_clock::time_point start_;
    std::chrono::steady_clock::time_point last_draw_{};
    bool activity_lines_;
    size_t count_ = 0;
    double fraction_ = 0.0;
    std::string item_, activity_;
    bool closed_ = false;
};

}  // namespace specbake
