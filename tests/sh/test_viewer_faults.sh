#!/bin/bash
# Faults around the viewer: each must give one clear line on stderr, exit status 1, no crash and
# no hang.
#   test_viewer_faults.sh display-lost   the X server dies under a running window (killed with
#                                        SIGTERM or SIGKILL, passes in flight or idle at the
#                                        target): "lost the connection to the X display"
#   test_viewer_faults.sh no-gl33        a display whose OpenGL stops at 3.0 (Mesa told so by
#                                        MESA_GL_VERSION_OVERRIDE): "offers no OpenGL 3.3 core
#                                        context", and no headless fallback
#   test_viewer_faults.sh headless-no-gl33   the same OpenGL under --headless: a PNG fails with
#                                        one line, a PFM (no OpenGL needed) is still written
#   test_viewer_faults.sh headless-no-osmesa   libOSMesa shadowed (LD_LIBRARY_PATH) by files that
#                                        do not load, then by a library without its functions: a PNG
#                                        fails with one line naming the library and the loader's
#                                        reason, a PFM is still written
# Needs AO_BINARY and AO_SOURCE_ROOT; the first two exit 77 without Xvfb (and xdotool).
. "$(dirname "$0")/lib.sh"
mode=${1:?mode}
scene=$root/assets/scenes/spheres.scene
server=
viewer=
cleanup() {
    [ -n "$viewer" ] && kill -9 "$viewer" 2>/dev/null
    [ -n "$server" ] && kill -9 "$server" 2>/dev/null
    rm -rf "$work"
}
trap cleanup EXIT

fail() {
    echo "FAIL: $*"
    echo "--- aoview stderr"; cat err.txt 2>/dev/null
    exit 1
}

need() {
    for tool in "$@"; do
        if ! command -v "$tool" >/dev/null; then
            echo "SKIP: $tool is not installed (Debian: apt-get install xvfb xdotool)"
            exit 77
        fi
    done
}

# Waits up to $2 seconds for process $1 to end; its exit status in $status, or fails.
wait_exit() {
    for _ in $(seq $(($2 * 20))); do
        kill -0 "$1" 2>/dev/null || break
        sleep 0.05
    done
    kill -0 "$1" 2>/dev/null && fail "aoview still running $2 s after the fault"
    wait "$1"
    status=$?
    viewer=
}

# Checks that err.txt is exactly one line matching the extended regex $1.
one_line() {
    [ "$(wc -l <err.txt)" -eq 1 ] && grep -Eq "$1" err.txt ||
        fail "stderr is not the one line /$1/"
}

# Starts an Xvfb of our own (the display number from -displayfd, so no race with other servers)
# and sets display to its name.
start_server() {
    rm -f display.txt
    Xvfb -displayfd 5 -screen 0 1280x1024x24 -nolisten tcp 5>display.txt >/dev/null 2>&1 &
    server=$!
    for _ in $(seq 100); do
        [ -s display.txt ] && break
        sleep 0.05
    done
    [ -s display.txt ] || fail "Xvfb did not start"
    display=:$(cat display.txt)
}

# One viewer on its own Xvfb, which is killed with signal $1 after $2 seconds of showing the
# window; aoview gets the other arguments.
lose_display() {
    local signal=$1 after=$2
    shift 2
    start_server
    DISPLAY=$display "$AO_BINARY" -q --size 160x120 --threads 2 "$@" "$scene" >/dev/null 2>err.txt &
    viewer=$!
    DISPLAY=$display timeout 20 xdotool search --sync --onlyvisible --name '^aoview' >/dev/null ||
        fail "no window appeared"
    sleep "$after"
    kill "-$signal" "$server"
    wait "$server" 2>/dev/null
    server=
    wait_exit "$viewer" 3
    [ "$status" -eq 1 ] || fail "exit status $status after losing the display ($signal, $*)"
    one_line "^aoview: lost the connection to the X display $display\$"
    echo "ok: Xvfb killed by SIG$signal after $after s ($*): $(cat err.txt)"
}

case $mode in
display-lost)
    need Xvfb xdotool
    lose_display TERM 0.5 --spp 1000000
    lose_display KILL 0.2 --spp 1000000
    lose_display TERM 1 --spp 4           # idle at the target, asleep waiting for events
    ;;
no-gl33)
    need Xvfb
    start_server
    # Mesa's software GLX, so that the override applies whatever GPU driver the machine has.
    DISPLAY=$display LIBGL_ALWAYS_SOFTWARE=1 MESA_GL_VERSION_OVERRIDE=3.0 \
        "$AO_BINARY" -q --size 80x60 --spp 1000000 "$scene" >/dev/null 2>err.txt &
    viewer=$!
    wait_exit "$viewer" 15
    [ "$status" -eq 1 ] || fail "exit status $status without OpenGL 3.3"
    one_line '^aoview: the X display :[0-9]+ offers no OpenGL 3\.3 core context \(.+\); --headless renders without a window$'
    [ -e aoview.png ] && fail "fell back to rendering headless"
    echo "ok: $(cat err.txt)"
    ;;
headless-no-gl33)
    MESA_GL_VERSION_OVERRIDE=3.0 "$AO_BINARY" --headless -q --size 40x30 --spp 4 -o out.png "$scene" 2>err.txt
    status=$?
    [ "$status" -eq 1 ] || fail "exit status $status for a PNG without OpenGL 3.3"
    one_line '^aoview: out\.png: no OpenGL 3\.3 core context from OSMesa$'
    [ -e out.png ] && fail "out.png written"
    echo "ok: $(cat err.txt)"
    MESA_GL_VERSION_OVERRIDE=3.0 "$AO_BINARY" --headless -q --size 40x30 --spp 4 -o out.pfm "$scene" 2>err.txt ||
        fail "no PFM without OpenGL 3.3"
    [ -s out.pfm ] || fail "out.pfm missing"
    echo "ok: the PFM needs no OpenGL"
    ;;
headless-no-osmesa)
    # Both names headless.c tries: empty files, which the loader refuses ("file too short").
    mkdir shadow && : >shadow/libOSMesa.so.8 && : >shadow/libOSMesa.so || fail "cannot make the stubs"
    # A PNG under the shadow: status 1, stderr the one line /$1/, no file left behind.
    png() {
        LD_LIBRARY_PATH=$work/shadow "$AO_BINARY" --headless -q --size 40x30 --spp 4 -o out.png "$scene" 2>err.txt
        status=$?
        [ "$status" -eq 1 ] || fail "exit status $status for a PNG without OSMesa"
        one_line "$1"
        [ -z "$(ls -A | grep -Ev '^(err\.txt|shadow)$')" ] || fail "files left behind: $(ls -A)"
        echo "ok: $(cat err.txt)"
    }
    png '^aoview: out\.png: cannot load OSMesa \(.*/shadow/libOSMesa\.so\.8: .+; .*/shadow/libOSMesa\.so: .+\)$'
    LD_LIBRARY_PATH=$work/shadow "$AO_BINARY" --headless -q --size 40x30 --spp 4 -o out.pfm "$scene" 2>err.txt ||
        fail "no PFM without OSMesa"
    [ -s out.pfm ] || fail "out.pfm missing"
    rm out.pfm
    echo "ok: the PFM needs no OSMesa"
    # A real library under OSMesa's name that lacks its functions: the C library's libm.
    libm=$(ldd "$AO_BINARY" | awk '$1 == "libm.so.6" { print $3 }')
    [ -f "$libm" ] || fail "libm.so.6 not found in ldd $AO_BINARY"
    rm shadow/libOSMesa.so.8 && ln -s "$libm" shadow/libOSMesa.so.8 || fail "cannot link $libm"
    png '^aoview: out\.png: cannot load OSMesa \(.*libm\.so\.6: undefined symbol: OSMesaCreateContextAttribs\)$'
    ;;
*)
    echo "unknown mode $mode"
    exit 2
    ;;
esac
echo "PASS ($mode)"
