# What the shell tests share, sourced first thing (. "$(dirname "$0")/lib.sh"): unset variables are
# errors; $bin and $root come from meson test's environment (AO_BINARY, AO_SOURCE_ROOT); $work is a
# scratch directory, the working directory from now on, removed on exit (a test that needs more
# cleanup sets its own EXIT trap and removes it there too); fail WHY counts a failure and goes on,
# and the test ends with `finish`: status 0 when nothing failed, else 1; skip WHY exits 77 (meson's
# skip) saying why.
set -u
bin=${AO_BINARY:?AO_BINARY not set (run it through meson test)}
root=${AO_SOURCE_ROOT:?AO_SOURCE_ROOT not set (run it through meson test)}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1
failures=0

fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
skip() { echo "SKIP: $*"; exit 77; }
finish() { exit $((failures > 0)); }
