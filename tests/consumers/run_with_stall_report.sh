#!/usr/bin/env bash
# Usage: run_with_stall_report.sh SECONDS COMMAND [ARGS...]
# Runs COMMAND and exits with its status. If it is still running after SECONDS, prints to stderr the
# thread stacks of it and of its child processes (gdb, where installed; else the kernel stacks), kills
# them and exits with 124, as timeout(1) does: a stall is then reported with where it stalled.
limit=$1
shift
"$@" &
pid=$!
for ((i = 0; i < limit * 10; i++)); do
    if ! kill -0 "$pid" 2>/dev/null; then
        wait "$pid"
        exit $?
    fi
    sleep 0.1
done
echo "stalled: still running after ${limit} s: $*" >&2
for p in "$pid" $(pgrep -P "$pid"); do
    echo "--- process $p: $(tr '\0' ' ' < "/proc/$p/cmdline" 2>/dev/null)" >&2
    if command -v gdb >/dev/null 2>&1; then
        timeout 60 gdb -p "$p" -batch -ex "thread apply all bt" 2>&1 | grep -v '^\[New LWP\|^warning:' | head -400 >&2
    else
        for t in /proc/"$p"/task/*; do echo "thread ${t##*/}:" >&2; cat "$t/stack" >&2 2>/dev/null; done
    fi
done
kill -9 "$pid" $(pgrep -P "$pid") 2>/dev/null
wait "$pid" 2>/dev/null
exit 124
