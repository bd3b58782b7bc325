// The progress display (see progress.h): one process-wide output lock, the bar on a terminal, plain lines
// otherwise.
#include "cli/progress.h"

#include "cli/run_settings.h"

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <mutex>

namespace specbake {

namespace {

std::mutex& output_mutex() {
    static std::mutex m;
    return m;
}

// The display whose bar is on the terminal now (at most one: commands show one at a time).
ProgressDisplay* active_bar = nullptr;
bool bar_visible = false;

void clear_bar_locked() {
    if (!bar_visible) return;
    std::fputs("\r\x1b[K", stderr);
    bar_visible = false;
}

int terminal_width() {
    winsize w{};
    if (::ioctl(STDERR_FILENO, TIOCGWINSZ, &w) == 0 && w.ws_col >= 20) return w.ws_col;
    return 80;
}

// m:ss, or h:mm:ss from an hour on.
std::string clock_time(double seconds) {
    const long s = std::lround(std::max(0.0, seconds));
    char text[32];
    if (s >= 3600) std::snprintf(text, sizeof text, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
    else std::snprintf(text, sizeof text, "%ld:%02ld", s / 60, s % 60);
    return text;
}

std::string seconds_text(double seconds) {
    char text[32];
    if (seconds < 60) std::snprintf(text, sizeof text, "%.1f s", seconds);
    else return clock_time(seconds);
    return text;
}

// "writing textures of material 0 of /lib/textures/t0001.gltf" -> "... of t0001.gltf": on one terminal line
// the file names say more than their folders.
std::string without_folders(const std::string& text) {
    std::string out;
    size_t at = 0;
    while (at < text.size()) {
        const size_t end = std::min(text.find(' ', at), text.size());
        const std::string word = text.substr(at, end - at);
        const size_t slash = word.find_last_of('/');
        out += slash == std::string::npos || slash + 1 == word.size() ? word : word.substr(slash + 1);
        if (end < text.size()) out += ' ';
        at = end + 1;
    }
    return out;
}

}  // namespace

ProgressMode progress_mode(const RunSettings& settings) {
    if (settings.verbosity == Verbosity::quiet) return ProgressMode::off;
    return settings.progress_bar ? ProgressMode::bar : ProgressMode::lines;
}

void print_line(std::FILE* stream, const std::string& line) {
    std::lock_guard lock(output_mutex());
    const bool redraw = bar_visible;
    clear_bar_locked();
    if (stream != stderr) std::fflush(stderr);
    std::fputs(line.c_str(), stream);
    std::fputc('\n', stream);
    std::fflush(stream);
    if (redraw && active_bar) {
        active_bar->draw_locked(true);  // the bar goes back right away, not at the next update
    }
}

ProgressDisplay::ProgressDisplay(size_t total, ProgressMode mode, std::string unit, Lines lines)
    : total_(total),
      mode_(mode),
      unit_(std::move(unit)),
      start_(std::chrono::steady_clock::now()),
      activity_lines_(lines == Lines::activity || (lines == Lines::automatic && total <= 1)) {
    if (mode_ == ProgressMode::bar) {
        std::lock_guard lock(output_mutex());
        active_bar = this;
    }
}

ProgressDisplay::~ProgressDisplay() { close(); }

size_t ProgressDisplay::count() const {
    std::lock_guard lock(output_mutex());
    return count_;
}

double ProgressDisplay::elapsed() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

std::string ProgressDisplay::timing(bool long_form) const {
    const double t = elapsed();
    const double done = total_ ? (double(count_) + std::clamp(fraction_, 0.0, 1.0)) / double(total_) : 1.0;
    std::string text = long_form ? seconds_text(t) + " elapsed" : clock_time(t) + " elapsed";
    if (done > 0.0 && done < 1.0) {
        const double left = t * (1.0 - done) / done;
        text += ", ~" + (long_form ? seconds_text(left) : clock_time(left)) + " left";
    }
    return text;
}

void ProgressDisplay::draw_locked(bool force) {
    if (mode_ != ProgressMode::bar || closed_) return;
    const auto now = std::chrono::steady_clock::now();
    // At most ten redraws a second: a batch of thousands of small assets must not spend its time drawing.
    if (!force && bar_visible && now - last_draw_ < std::chrono::milliseconds(100)) return;
    last_draw_ = now;
    constexpr size_t kBar = 20;
    const double done = total_ ? (double(count_) + std::clamp(fraction_, 0.0, 1.0)) / double(total_) : 1.0;
    const size_t filled = std::min(kBar, size_t(done * double(kBar)));
    std::string bar(filled, '=');
    if (filled < kBar) bar += '>';
    bar.resize(kBar, ' ');
    std::string line = "[" + bar + "] " + std::to_string(count_) + "/" + std::to_string(total_) + " " + unit_;
    const std::string times = "  " + timing(false);
    std::string current = without_folders(item_);
    if (!activity_.empty()) current += (current.empty() ? "" : ": ") + without_folders(activity_);
    const size_t width = size_t(terminal_width()) - 1;
    const size_t room = width > line.size() + times.size() + 2 ? width - line.size() - times.size() - 2 : 0;
    if (current.size() > room) current = room > 3 ? "..." + current.substr(current.size() - (room - 3)) : "";
    if (!current.empty()) line += "  " + current;
    line += times;
    if (line.size() > width) line.resize(width);
    std::fputs(("\r" + line + "\x1b[K").c_str(), stderr);
    std::fflush(stderr);
    bar_visible = true;
    active_bar = this;
}

void ProgressDisplay::status(const std::string& item, const std::string& activity) {
    if (mode_ == ProgressMode::off) return;
    std::lock_guard lock(output_mutex());
    if (mode_ == ProgressMode::lines) {
        if (activity_lines_ && !activity.empty()) std::fprintf(stderr, "specbake: %s\n", activity.c_str());
        return;
    }
    item_ = item;
    activity_ = activity;
    draw_locked(false);
}

void ProgressDisplay::fraction(double done) {
    if (mode_ != ProgressMode::bar) return;
    std::lock_guard lock(output_mutex());
    fraction_ = done;
    draw_locked(false);
}

void ProgressDisplay::finished(const std::string& item, const char* word) {
    std::lock_guard lock(output_mutex());
    ++count_;
    fraction_ = 0.0;
    if (mode_ == ProgressMode::lines && !activity_lines_) {
        std::fprintf(stderr, "[%zu/%zu] %s %s (%s)\n", count_, total_, word, item.c_str(), timing(true).c_str());
    } else if (mode_ == ProgressMode::bar) {
        if (item_ == item) activity_.clear();
        draw_locked(count_ == total_);
    }
}

void ProgressDisplay::close() {
    std::lock_guard lock(output_mutex());
    if (closed_) return;
    closed_ = true;
    if (active_bar == this) {
        clear_bar_locked();
        active_bar = nullptr;
    }
}

}  // namespace specbake
