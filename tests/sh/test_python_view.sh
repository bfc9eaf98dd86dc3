#!/usr/bin/env bash
# window suite: aoview.view() from Python opens aoview's own window on a scene made from arrays
# (its title names the scene and counts its samples), renders it to the end, and returns None when
# Q is pressed; without a display it raises RuntimeError. Needs AO_PYTHON, PYTHONPATH (meson sets
# them); exits 77 when Xvfb or xdotool is missing.
set -u
for tool in xvfb-run xdotool; do
    if ! command -v "$tool" >/dev/null; then
        echo "SKIP: $tool is not installed (Debian: apt-get install xvfb xdotool)"
        exit 77
    fi
done
if [ -z "${AO_UNDER_XVFB:-}" ]; then
    # Without a display first: RuntimeError, no crash.
    out=$(env -u DISPLAY "$AO_PYTHON" -c '
import aoview
scene = aoview.Scene.from_arrays([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
try:
    aoview.view(scene, size=(64, 48))
except RuntimeError as error:
    print("raised:", error)' 2>&1)
    case $out in
        *"raised: aoview: no display"*) ;;
        *) echo "FAIL: view() without a display: $out"; exit 1 ;;
    esac
    # A 24-bit screen: xvfb-run's default depth has no OpenGL visual.
    AO_UNDER_XVFB=1 exec xvfb-run -a -s "-screen 0 1280x1024x24" "$0" "$@"
fi
. "$(dirname "$0")/lib.sh"

"$AO_PYTHON" -c '
import aoview
import numpy as np
x, z = np.meshgrid(np.linspace(-1, 1, 9), np.linspace(-1, 1, 9))
v = np.stack([x.ravel(), 0.2 * np.sin(3 * x.ravel()) * np.cos(2 * z.ravel()), z.ravel()], axis=1)
f = [[j * 9 + i, (j + 1) * 9 + i, j * 9 + i + 1] for j in range(8) for i in range(8)] + \
    [[j * 9 + i + 1, (j + 1) * 9 + i, (j + 1) * 9 + i + 1] for j in range(8) for i in range(8)]
scene = aoview.Scene.from_arrays(v, f, spheres=[((0, 0.5, 0), 0.3)], name="pyview")
print("returned", aoview.view(scene, size=(320, 240), spp=64))' >"$work/stdout" 2>"$work/stderr" &
pid=$!
wid=""
for _ in $(seq 200); do
    wid=$(xdotool search --name 'pyview' 2>/dev/null | head -1)
    [ -n "$wid" ] && break
    sleep 0.05
done
[ -n "$wid" ] || fail "no window named pyview within 10 s"
done_title=""
for _ in $(seq 400); do
    title=$(xdotool getwindowname "$wid" 2>/dev/null)
    case $title in *" — finished — "*) done_title=$title; break ;; esac
    sleep 0.05
done
[ -n "$done_title" ] || fail "the title never said the run finished: $(xdotool getwindowname "$wid" 2>/dev/null)"
echo "title: $done_title"
xdotool key --window "$wid" q 2>/dev/null   # the key-up finds the window gone: said on stderr
for _ in $(seq 200); do
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.05
done
if kill -0 "$pid" 2>/dev/null; then
    kill "$pid"
    fail "view() did not return within 10 s of Q"
fi
wait "$pid" || fail "python exited with status $?: $(cat "$work/stderr")"
grep -q '^returned None$' "$work/stdout" || fail "view() did not return None: $(cat "$work/stdout" "$work/stderr")"
cat "$work/stdout"
finish
