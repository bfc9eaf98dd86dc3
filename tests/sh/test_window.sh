#!/bin/bash
# window suite: the real viewer in a real X window under Xvfb, driven by xdotool.
#   test_window.sh keys    presses C, U, A, S, +, R, G, E, N, F, D, Esc in turn and checks the
#                          title, the screenshot files (E: the error map; N: the normals view,
#                          F: flat normals on the scene's octahedron; D without a reference:
#                          nothing but a message) and a clean exit within a second of Esc
#   test_window.sh stress  200 random keys, drags and resizes in a few seconds, then a screenshot
#                          (no NaN in its PFM) and a clean exit
#   test_window.sh chart   with --reference: a run in each sampling mode (H, then U, then C) leaves
#                          a curve in its colour on the screen (and nothing in a colour of a run
#                          not made), read from Xvfb's framebuffer file;
#                          F2 hides the chart; D shows the difference heat map
#   test_window.sh resize  the render follows the window: a resize restarts once at the new size
#                          (title, --stats, S's PNG), ] and [ double and halve the pixel size, a
#                          resize during V keeps both sides one size; --pixel-size 2 halves it
#   test_window.sh compare V: uniform against cosine, labelled on both sides, both curves in the
#                          chart, render seconds within 5 %; B, divider drag, S (screenshots of
#                          both layouts compared), E, D, +, G restart nothing, an orbit, a pan and
#                          a zoom each restart both; V again; --compare at start with --time and
#                          --stats, fair within 5 %, and an orbit once it has finished
#   test_window.sh truth   only measured figures: titles read every 0.1 s after a resize show no
#                          error, RMSE or convergence while a preview is on screen, no time left or
#                          rate before the first pass; E before any
#                          tile has an estimate paints them all "not known"; a --size too large
#                          for the screen says so on one line; the chart keeps every pass of a
#                          run faster than the window, its legend the runs made; --pixel-size
#                          auto is 2 where Xft.dpi says the content scale is 2
#   test_window.sh frames  every finished pass on screen: the bunny at 640x480, --spp 256, watched
#                          from the X server by tools/window_frames.c (its bounds derived there)
#   test_window.sh start   --spppp 4096: an image within 0.5 s, A on screen during the first pass,
#                          and Q, Esc and closing the window each ending the run within 0.2 s
# Needs AO_BINARY and AO_SOURCE_ROOT (tests/meson.build sets both); exits 77 when Xvfb or
# xdotool is missing.
set -u
mode=${1:-keys}

for tool in xvfb-run xdotool python3; do
    if ! command -v "$tool" >/dev/null; then
        echo "SKIP: $tool is not installed (Debian: apt-get install xvfb xdotool)"
        exit 77
    fi
done
if [ "$mode" = truth ] && ! command -v xprop >/dev/null; then
    echo "SKIP: xprop is not installed (Debian: apt-get install x11-utils)"
    exit 77
fi
if [ -z "${AO_UNDER_XVFB:-}" ]; then
    # A 24-bit screen: xvfb-run's default depth has no OpenGL visual. The server keeps its screen
    # in an XWD file under AO_FBDIR, which the chart test reads.
    AO_FBDIR=$(mktemp -d)
    export AO_FBDIR
    # truth sets a property on the root window between launches: the server must not reset when
    # its last client leaves.
    noreset=""
    if [ "$mode" = truth ]; then
        noreset=-noreset
    fi
    AO_UNDER_XVFB=1 exec xvfb-run -a -s "-screen 0 1280x1024x24 -fbdir $AO_FBDIR $noreset" "$0" "$@"
fi
. "$(dirname "$0")/lib.sh"

# A sanitizer's build traces some 12 times slower (ThreadSanitizer: the bunny at 1000x700 on one
# thread, 1.4 Mrays/s where the release build does 16.6), so that what a title waits for (11 spp
# after a resize, in truth) can take longer than 10 s: its waits are four times as long.
patience=1
if ldd "$AO_BINARY" 2>/dev/null | grep -qE 'lib(asan|tsan)'; then patience=4; fi

if [ "$mode" = frames ] || [ "$mode" = start ]; then
    [ -n "${AO_WINDOW_FRAMES:-}" ] ||
        skip "tools/window_frames was not built: it needs XTEST and XDAMAGE (Debian: libxtst-dev libxdamage-dev)"
    bunny=$root/assets/scenes/bunny.scene
    if [ "$mode" = frames ]; then
        "$AO_WINDOW_FRAMES" frames --patience $patience "$AO_BINARY" --size 640x480 --spp 256 "$bunny" ||
            fail "passes missing from the screen"
    else
        # ThreadSanitizer sleeps 1 s at exit when a thread it knows of is still alive, to catch
        # races with exit; Embree's TBB workers end on their own after the device is released, so
        # some runs meet that sleep and some do not. The time to the end measured here is
        # aoview's, not the sanitizer's: no sleep.
        export TSAN_OPTIONS="${TSAN_OPTIONS:-}:atexit_sleep_ms=0"
        for key in q Escape close; do
            "$AO_WINDOW_FRAMES" start --patience $patience "$key" "$AO_BINARY" --size 640x480 --spppp 4096 \
                --spp 65536 "$bunny" || fail "$key"
        done
    fi
    finish
fi

fail() {
    echo "FAIL: $*"
    echo "last title: $(xdotool getwindowname "$wid" 2>/dev/null)"
    echo "--- aoview stdout"; cat "$work/stdout"
    echo "--- aoview stderr"; cat "$work/stderr"
    exit 1
}

title() { xdotool getwindowname "$wid"; }

# Polls the title until it matches the extended regex $1, for at most 10 s (times patience).
wait_title() {
    for _ in $(seq $((200 * patience))); do
        [[ $(title) =~ $1 ]] && return 0
        sleep 0.05
    done
    fail "title never matched /$1/"
}

# The number in the title's "pass N".
pass() { [[ $(title) =~ pass\ ([0-9]+) ]] && echo "${BASH_REMATCH[1]}"; }
# True when one reading of the title shows more samples than passes (both from the same title:
# two readings could straddle a new frame).
spp_ahead() {
    local t spp
    t=$(title)
    [[ $t =~ mean\ ([0-9]+)\ spp ]] && spp=${BASH_REMATCH[1]} && [[ $t =~ pass\ ([0-9]+) ]] &&
        [ "$spp" -gt "${BASH_REMATCH[1]}" ]
}

# Presses the keys (X keysym names) on the focused viewer, as a user would.
press() {
    xdotool windowfocus --sync "$wid" key --delay 20 "$@" 2>/dev/null
}

# Waits for screenshot number $1 and checks that both files decode: PNG signature and IHDR size
# ($2 wide, else W; $3 high, else H), PFM header, size and no NaN or infinity among its floats.
check_screenshot() {
    local png="$work/aoview-$1.png" pfm="$work/aoview-$1.pfm"
    for _ in $(seq 200); do
        [ -s "$png" ] && [ -s "$pfm" ] && break
        sleep 0.05
    done
    python3 - "$png" "$pfm" "${2:-$W}" "${3:-$H}" <<'EOF' || fail "screenshot $1 does not decode"
import math, struct, sys
png, pfm, w, h = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
data = open(png, 'rb').read()
assert data[:8] == b'\x89PNG\r\n\x1a\n', 'no PNG signature'
assert data[12:16] == b'IHDR' and struct.unpack('>II', data[16:24]) == (w, h), ('PNG size', struct.unpack('>II', data[16:24]), w, h)
data = open(pfm, 'rb').read()
header = data.split(b'\n', 3)
assert header[0] == b'PF' and header[1].split() == [str(w).encode(), str(h).encode()], 'PFM header'
scale = float(header[2])
pixels = header[3]
assert len(pixels) == 12 * w * h, 'PFM size'
values = struct.unpack(('<' if scale < 0 else '>') + 'f' * (3 * w * h), pixels)
bad = [v for v in values if not math.isfinite(v)]
assert not bad, '%d non-finite values' % len(bad)
EOF
}

# The number of distinct colours in PNG $1 (8-bit RGB, any filter), read with zlib alone, and the
# share of its pixels that are not grey (channels more than 24 apart).
png_stats() {
    python3 - "$1" <<'EOF'
import struct, sys, zlib
data = open(sys.argv[1], 'rb').read()
pos, idat, w, h = 8, b'', 0, 0
while pos < len(data):
    n, kind = struct.unpack('>I4s', data[pos:pos + 8])
    if kind == b'IHDR':
        w, h = struct.unpack('>II', data[pos + 8:pos + 16])
    elif kind == b'IDAT':
        idat += data[pos + 8:pos + 8 + n]
    pos += 12 + n
raw, stride, prev, colours, coloured = zlib.decompress(idat), 3 * w, bytearray(3 * w), set(), 0
for y in range(h):
    kind, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
    for x in range(stride):
        a, b, c = line[x - 3] if x >= 3 else 0, prev[x], prev[x - 3] if x >= 3 else 0
        p = a + b - c
        pred = [0, a, b, (a + b) // 2,
                a if abs(p - a) <= abs(p - b) and abs(p - a) <= abs(p - c) else b if abs(p - b) <= abs(p - c) else c][kind]
        line[x] = (line[x] + pred) & 255
    colours.update(bytes(line[i:i + 3]) for i in range(0, stride, 3))
    coloured += sum(max(line[i:i + 3]) - min(line[i:i + 3]) > 24 for i in range(0, stride, 3))
    prev = line
print(len(colours), coloured / (w * h))
EOF
}
png_colours() { png_stats "$1" | cut -d' ' -f1; }

# Counts the pixels of PFM $1 within 1e-4 of the colour ($2, $3, $4), and those that differ by more
# than 0.01 in some channel from PFM $5 (or 0 without it); then the mean absolute difference.
pfm_count() {
    python3 - "$@" <<'EOF'
import struct, sys
def read(path):
    header = open(path, 'rb').read().split(b'\n', 3)
    w, h = map(int, header[1].split())
    return struct.unpack('<' + 'f' * (3 * w * h), header[3])
a = read(sys.argv[1])
colour = [float(x) for x in sys.argv[2:5]]
pixels = [a[i:i + 3] for i in range(0, len(a), 3)]
same = sum(all(abs(p[c] - colour[c]) < 1e-4 for c in range(3)) for p in pixels)
differ, mean = 0, 0.0
if len(sys.argv) > 5:
    b = read(sys.argv[5])
    differ = sum(any(abs(a[i + c] - b[i + c]) > 0.01 for c in range(3)) for i in range(0, len(a), 3))
    mean = sum(abs(x - y) for x, y in zip(a, b)) / len(a)
print(same, differ, mean)
EOF
}

# Counts, in the part of the window on the screen from LEFT to RIGHT % of its width and TOP to
# BOTTOM % of its height, the pixels of each colour R,G,B given (within 8 in each channel), read
# from Xvfb's framebuffer file: screen_colours LEFT TOP RIGHT BOTTOM R,G,B...
screen_colours() {
    eval "$(xdotool getwindowgeometry --shell "$wid")"
    python3 - "$AO_FBDIR/Xvfb_screen0" "$X" "$Y" "$WIDTH" "$HEIGHT" "$@" <<'EOF'
import struct, sys
path, x0, y0, w, h, left, top, right, bottom = sys.argv[1], *map(int, sys.argv[2:10])
colours = [tuple(map(int, c.split(','))) for c in sys.argv[10:]]
data = open(path, 'rb').read()
header = struct.unpack('>25I', data[:100])
size, bits, stride, ncolours = header[0], header[11], header[12], header[19]
assert bits == 32 and header[7] == 0 and header[14:17] == (0xff0000, 0xff00, 0xff), 'not 24-bit BGRX'
pixels = size + 12 * ncolours
counts = [0] * len(colours)
for y in range(y0 + h * top // 100, y0 + h * bottom // 100):
    row = pixels + y * stride
    for x in range(x0 + w * left // 100, x0 + w * right // 100):
        b, g, r = data[row + 4 * x:row + 4 * x + 3]
        for i, (cr, cg, cb) in enumerate(colours):
            if abs(r - cr) <= 8 and abs(g - cg) <= 8 and abs(b - cb) <= 8:
                counts[i] += 1
print(*counts)
EOF
}

# The pixels in each sampling mode's chart colour (chartview.c's MODE_COLOUR) in the window's
# bottom right quarter: the counts for uniform, hemisphere and cosine, "0 0 0" without a chart.
chart_colours() { screen_colours 50 50 100 100 255,128,0 0,255,64 0,191,255; }

# The pixels of the overlay's text colour (hud.c's, 1 1 0.85) in the window's top left and top
# right quarters.
label_pixels() {
    echo "$(screen_colours 0 0 50 50 255,255,217) $(screen_colours 50 0 100 50 255,255,217)"
}

# The numbers of the comparison's title: A's spp and seconds, then B's.
sides() {
    local side='[^ ]+  ([0-9]+) spp  ([0-9.e+]+) s'
    [[ $(title) =~ A:\ $side.*B:\ $side ]] &&
        echo "${BASH_REMATCH[1]} ${BASH_REMATCH[2]} ${BASH_REMATCH[3]} ${BASH_REMATCH[4]}"
}

# Starts the viewer with the arguments given, its output to stdout and stderr in the work folder,
# and waits for its window: pid and wid name them. $1 says what for, in the failure.
open_viewer() {
    local what=$1
    shift
    "$AO_BINARY" "$@" >stdout 2>stderr &
    pid=$!
    wid=$(timeout 20 xdotool search --sync --onlyvisible --name '^aoview') || fail "no window for $what"
    wid=${wid%%$'\n'*}
}

# Drags with the left button from ($1, $2) to ($3, $4) in the window, pausing between the steps as
# a hand would.
drag() {
    xdotool mousemove --window "$wid" "$1" "$2"
    sleep 0.2
    xdotool mousedown 1
    sleep 0.2
    xdotool mousemove --window "$wid" "$3" "$4"
    sleep 0.2
    xdotool mouseup 1
    sleep 0.3
}

# Starts the viewer on the small spheres scene with a target it will not reach; for the chart,
# at a size that leaves it room and against a reference made first.
W=160
H=120
trap 'kill "$pid" 2>/dev/null; rm -rf "$work" "$AO_FBDIR"' EXIT
args=()
scene=$root/assets/scenes/spheres.scene
if [ "$mode" = keys ]; then
    # The spheres and, for F, a coarse mesh: an octahedron whose vertex normals point outwards.
    cat >octahedron.obj <<'EOF'
v 1 0 0
v -1 0 0
v 0 1 0
v 0 -1 0
v 0 0 1
v 0 0 -1
vn 1 0 0
vn -1 0 0
vn 0 1 0
vn 0 -1 0
vn 0 0 1
vn 0 0 -1
f 1//1 3//3 5//5
f 5//5 3//3 2//2
f 2//2 3//3 6//6
f 6//6 3//3 1//1
f 5//5 4//4 1//1
f 2//2 4//4 5//5
f 6//6 4//4 2//2
f 1//1 4//4 6//6
EOF
    { cat "$scene"; echo "mesh octahedron.obj scale 0.4 translate 1.2 0.4 0.8"; } >keys.scene
    scene=$work/keys.scene
fi
if [ "$mode" = chart ] || [ "$mode" = compare ]; then
    W=320
    H=240
    # The comparison at 80x60, shown 8 times magnified: passes short enough (a fraction of a
    # millisecond, a few under ThreadSanitizer) that one pass is a small part of the 5 % bound.
    if [ "$mode" = compare ]; then
        W=80
        H=60
    fi
    "$AO_BINARY" --headless -q --size ${W}x$H --spp 64 --spppp 16 -o ref.pfm \
        "$scene" || { echo "FAIL: no reference"; exit 1; }
    args=(--reference ref.pfm)
fi
if [ "$mode" = resize ]; then
    # At 640x480 the window is the image's size; every pixel is rendered.
    W=640
    H=480
    args=(--pixel-size 1 --stats stats.csv)
fi
threads=2
if [ "$mode" = truth ]; then
    # The bunny on one thread: passes of some 50 ms at 1000x700, so that the preview a restart
    # shows stays on screen for several readings of the title (until 11 spp); a reference, so that
    # an RMSE is there to show once it is measured.
    W=800
    H=600
    threads=1
    scene=$AO_SOURCE_ROOT/assets/scenes/bunny.scene
    "$AO_BINARY" --headless -q --size ${W}x$H --spp 16 --spppp 16 -o ref.pfm "$scene" ||
        { echo "FAIL: no reference"; exit 1; }
    args=(--pixel-size 1 --reference ref.pfm)
fi
# Adaptive sampling off, so that G turns it on.
"$AO_BINARY" --size ${W}x$H --spp 1000000 --spppp 1 --threads $threads --sampling hemisphere --adaptive off \
    "${args[@]}" "$scene" >stdout 2>stderr &
pid=$!
wid=$(timeout 20 xdotool search --sync --onlyvisible --name '^aoview') || fail "no window appeared"
wid=${wid%%$'\n'*}
wait_title "hemisphere — AA on — mean [0-9]+ spp, up to 1000000 — "

if [ "$mode" = keys ]; then
    # Sampling and anti-aliasing: each key shows in the title of the next frame.
    press c
    wait_title " — cosine — AA on — "
    press u
    wait_title " — uniform — AA on — "
    press a
    wait_title " — uniform — AA off — "

    # S: both files, named for the first free number, reported on stdout.
    press s
    check_screenshot 1
    grep -q "aoview-1.png" stdout || fail "screenshot names not printed"

    # +: two samples per pass, so spp runs ahead of the pass count.
    press plus
    wait_title " — 2 spp/pass"
    for _ in $(seq 200); do
        spp_ahead && break
        sleep 0.05
    done
    spp_ahead || fail "+ did not raise the samples per pass"

    # R: the pass count starts again from 1.
    wait_title " — pass ([6-9]|[1-9][0-9]+) — "
    before=$(pass)
    press r
    for _ in $(seq 200); do
        [ "$(pass)" -lt "$before" ] && break
        sleep 0.05
    done
    [ "$(pass)" -lt "$before" ] || fail "R did not restart (pass stayed at or above $before)"

    # G: adaptive sampling, told in the title. E: the estimated error map, one colour per 16x16
    # tile (10 x 8 of them here), saved by S as displayed; E again: the image, in many shades.
    press g
    wait_title " — adaptive: [0-9]+ % converged"
    press e
    sleep 0.5
    press s
    check_screenshot 2
    colours=$(png_colours "$work/aoview-2.png")
    [ "$colours" -le 80 ] || fail "E did not show the error map ($colours colours)"
    press e
    sleep 0.5
    press s
    check_screenshot 3
    colours=$(png_colours "$work/aoview-3.png")
    [ "$colours" -gt 80 ] || fail "E again did not show the image ($colours colours)"

    # N: the normals view, a restart; the ground shows (n + 1) / 2 = (0.5, 1, 0.5) exactly (AA is
    # off since A above, so the images below are exact pass after pass).
    press n
    wait_title " — AA off — normals — "
    sleep 0.5
    press s
    check_screenshot 4
    read -r ground _ _ < <(pfm_count "$work/aoview-4.pfm" 0.5 1 0.5)
    [ "$ground" -ge $((W * H / 4)) ] || fail "N did not show the normals ($ground ground pixels)"
    # F: flat normals; only the octahedron's pixels change, and a few hundred of them show.
    press f
    wait_title " — normals — flat — "
    sleep 0.5
    press s
    check_screenshot 5
    read -r _ changed _ < <(pfm_count "$work/aoview-5.pfm" 0.5 1 0.5 "$work/aoview-4.pfm")
    [ "$changed" -ge 50 ] || fail "F did not change the normals ($changed pixels changed)"
    # D without a reference: a message on stdout, and the same image as before.
    press d
    sleep 0.5
    grep -q "D shows the difference from --reference; none was given" stdout || fail "D without a reference said nothing"
    kill -0 "$pid" 2>/dev/null || fail "D without a reference killed the viewer"
    press s
    check_screenshot 6
    cmp -s "$work/aoview-5.png" "$work/aoview-6.png" || fail "D without a reference changed the image"
elif [ "$mode" = chart ]; then
    # The legend names the modes of the runs made, hemisphere's alone at first; each run's curve
    # (and its mode's name) adds to its mode's count. Each run lasts 1.5 s: scores of frames, a
    # line across most of the plot.
    wait_title " — RMSE [0-9.e-]+"
    sleep 1.5
    read -r u0 h0 c0 < <(chart_colours)
    press u
    wait_title " — uniform — .* — RMSE "
    sleep 1.5
    read -r u1 h1 c1 < <(chart_colours)
    press c
    wait_title " — cosine — .* — RMSE "
    sleep 1.5
    read -r u2 h2 c2 < <(chart_colours)
    echo "chart colour pixels (uniform hemisphere cosine): H run $u0 $h0 $c0, U run $u1 $h1 $c1, C run $u2 $h2 $c2"
    [ "$h0" -gt 0 ] && [ "$u0" -le 3 ] && [ "$c0" -le 3 ] || fail "the chart does not show the runs made alone"
    [ $((u1 - u0)) -ge 30 ] || fail "no uniform curve after U"
    [ $((c2 - c1)) -ge 30 ] || fail "no cosine curve after C"
    [ $((u2 - u0)) -ge 30 ] || fail "the uniform run's curve was not kept after C"
    press F2
    sleep 0.5
    read -r u3 h3 c3 < <(chart_colours)
    [ $((u3 + h3 + c3)) -le 3 ] || fail "F2 left the chart on screen ($u3 $h3 $c3)"
    # D: the difference heat map, in colour nearly everywhere (the image itself is mostly grey);
    # S still saves the linear image as the PFM, close to the reference (a heat map's colours are
    # not: its darkest is 0.06 in blue, the image about 0.5 to 1).
    press s
    check_screenshot 1
    press d
    sleep 0.5
    press s
    check_screenshot 2
    read -r _ image_share < <(png_stats "$work/aoview-1.png")
    read -r _ heat_share < <(png_stats "$work/aoview-2.png")
    echo "coloured share: image $image_share, difference $heat_share"
    python3 -c "import sys; sys.exit(not (float('$heat_share') > 0.8 and float('$image_share') < 0.5))" ||
        fail "D did not show the difference heat map"
    read -r _ _ mean < <(pfm_count "$work/aoview-2.pfm" 0 0 0 "$work/ref.pfm")
    python3 -c "import sys; sys.exit(not float('$mean') < 0.05)" || fail "D changed the saved PFM (mean difference $mean)"
elif [ "$mode" = compare ]; then
    # Neither uniform's nor cosine's colour in the chart yet (it has a hemisphere run alone).
    wait_title " — RMSE [0-9.e-]+"
    sleep 1
    read -r u0 _ c0 < <(chart_colours)
    read -r _ right0 < <(label_pixels)
    # V after U: uniform against its partner, cosine, each side labelled at its top.
    press u
    wait_title " — uniform — AA on — "
    press v
    wait_title " — compare — A: uniform\+sobol\+aa  [0-9]+ spp  [0-9.]+ s  RMSE [0-9.e-]+ — B: cosine\+sobol\+aa  [0-9]+ spp  [0-9.]+ s  RMSE "
    sleep 2
    read -r left1 right1 < <(label_pixels)
    read -r u1 _ c1 < <(chart_colours)
    echo "label text pixels: top right $right0 before V; top left $left1, top right $right1 after"
    echo "chart pixels after V (uniform, cosine): $u1 $c1, before $u0 $c0"
    [ "$left1" -ge 100 ] && [ "$right1" -ge 100 ] && [ "$right0" -lt 20 ] || fail "no label on each side"
    [ $((u1 - u0)) -ge 30 ] && [ $((c1 - c0)) -ge 30 ] || fail "the chart does not show both sides' curves"

    # Fairness: the two sides' render seconds within 5 % of each other (the turns keep them within
    # one pass, a few ms here). The sides share the wall clock, and the title's figures are renewed
    # twice a second: 3 s after the labels each side shows at least (3 - 0.5) / 2 = 1.25 s.
    sleep 1
    read -r spp_a sec_a spp_b sec_b < <(sides)
    echo "after 3 s: A $spp_a spp $sec_a s, B $spp_b spp $sec_b s"
    python3 -c "import sys; a, b = $sec_a, $sec_b; sys.exit(not (a >= 1 and abs(a - b) <= 0.05 * max(a, b)))" ||
        fail "the sides' render times differ by more than 5 % ($sec_a s, $sec_b s)"

    # Paused, nothing runs and nothing restarts: B (side by side), S, B again (split), a divider
    # drag to a quarter of the width, S, E, D. The screenshots: side by side twice as wide, A left
    # and B right; split, A's columns left of the divider and B's right of it.
    press space
    wait_title " — paused$"
    sleep 0.5   # the pass in flight ends and shows
    paused=$(title)
    press b
    sleep 0.5
    press s
    check_screenshot 1 $((2 * W))
    press b
    sleep 0.3
    eval "$(xdotool getwindowgeometry --shell "$wid")"
    drag $((WIDTH / 2)) $((HEIGHT / 2)) $((WIDTH / 4)) $((HEIGHT / 2))
    press s
    check_screenshot 2
    press e e d d
    sleep 0.5
    [ "$(title)" = "$paused" ] || fail "B, the divider, S, E or D changed the paused comparison: $(title)"
    python3 - "$work/aoview-1.pfm" "$work/aoview-2.pfm" "$W" <<'EOF' || fail "the screenshots do not show the layouts"
import struct, sys
def read(path):
    header = open(path, 'rb').read().split(b'\n', 3)
    w, h = map(int, header[1].split())
    v = struct.unpack('<' + 'f' * (3 * w * h), header[3])
    return w, h, [[v[3 * (y * w + x):3 * (y * w + x) + 3] for x in range(w)] for y in range(h)]
W = int(sys.argv[3])
bw, bh, both = read(sys.argv[1])
sw, sh, split = read(sys.argv[2])
a = [row[:W] for row in both]
b = [row[W:] for row in both]
assert (bw, sw) == (2 * W, W), (bw, sw)
differ = sum(a[y][x] != b[y][x] for y in range(sh) for x in range(W))
assert differ > W * sh // 4, 'sides alike: %d pixels differ' % differ
# PFM rows run bottom to top; columns are what the divider splits.
from_a = [all(split[y][x] == a[y][x] for y in range(sh)) for x in range(W)]
from_b = [all(split[y][x] == b[y][x] for y in range(sh)) for x in range(W)]
column = next(x for x in range(W + 1) if x == W or not from_a[x])
assert all(from_b[column:]), 'columns right of %d are not all B' % column
print('divider at column %d of %d' % (column, W))
assert 0.2 * W <= column <= 0.3 * W, column
EOF

    # Running again, + and G change no estimate: the sides go on from their spp.
    press space
    sleep 0.5
    read -r before _ _ _ < <(sides)
    press plus g
    sleep 0.5
    read -r after _ _ _ < <(sides)
    [ "$after" -ge "$before" ] || fail "+ or G restarted the comparison ($before spp, then $after)"
    # Each camera move restarts both sides: an orbit away from the divider, a pan, a wheel step.
    for move in orbit pan zoom; do
        sleep 1.5
        read -r spp_a _ spp_b _ < <(sides)
        case $move in
        orbit) drag $((3 * WIDTH / 4)) $((HEIGHT / 2)) $((3 * WIDTH / 4 + 40)) $((HEIGHT / 2)) ;;
        pan) xdotool mousemove --window "$wid" $((3 * WIDTH / 4)) $((HEIGHT / 2)) mousedown 3
             sleep 0.2
             xdotool mousemove --window "$wid" $((3 * WIDTH / 4)) $((HEIGHT / 2 + 30))
             sleep 0.2
             xdotool mouseup 3 ;;
        zoom) xdotool mousemove --window "$wid" $((3 * WIDTH / 4)) $((HEIGHT / 2)) click 4 ;;
        esac
        # Restarted, each side is back below the spp it had 1.5 s into its run; else its spp only
        # grows. So any reading below proves the restart, and the title is read every 0.1 s for
        # 1 s (a restarted side takes about 1.5 s to climb back, so no restart is missed; a GL
        # thread that a sanitizer and a busy machine hold up for a few tenths is waited for).
        for _ in 1 2 3 4 5 6 7 8 9 10; do
            sleep 0.1
            read -r new_a _ new_b _ < <(sides)
            [ "$new_a" -lt "$spp_a" ] && [ "$new_b" -lt "$spp_b" ] && break
        done
        echo "$move: A $spp_a -> $new_a spp, B $spp_b -> $new_b spp"
        [ "$new_a" -lt "$spp_a" ] && [ "$new_b" -lt "$spp_b" ] || fail "a $move did not restart both sides"
    done
    # V again: the single view, in A's configuration.
    press v
    wait_title "spheres.scene — [0-9]+x[0-9]+ — uniform — AA on — mean [0-9]+ spp, up to 1000000 — "
    press Escape
    wait "$pid" || fail "exit status $? after Esc"

    # --compare at start, for --time 1.5 s a side: the comparison finishes with both sides' render
    # seconds, per --stats, within 5 % of each other.
    "$AO_BINARY" --size ${W}x$H --spppp 1 --threads 2 --adaptive off --compare cosine+random,cosine+sobol \
        --time 1.5 --stats stats.csv "$scene" >stdout 2>stderr &
    pid=$!
    wid=$(timeout 20 xdotool search --sync --onlyvisible --name '^aoview') || fail "no window for --compare"
    wid=${wid%%$'\n'*}
    wait_title " — compare — A: cosine\+random\+aa  .* — B: cosine\+sobol\+aa  .* — finished$"
    python3 - <<'EOF' || fail "the sides' render times per --stats differ by more than 5 %"
import csv
rows = list(csv.reader(open('stats.csv')))
assert rows[0][:2] == ['side', 'pass'], rows[0]
last = {r[0]: r for r in rows[1:]}
a, b = float(last['A'][3]), float(last['B'][3])
print('--compare --time 1.5: A %.3f s %s spp, B %.3f s %s spp' % (a, last['A'][2], b, last['B'][2]))
assert max(a, b) >= 1.5 and abs(a - b) <= 0.05 * max(a, b), (a, b)
EOF
    # Finished, an orbit starts both sides over, and they finish again.
    read -r spp_a _ spp_b _ < <(sides)
    eval "$(xdotool getwindowgeometry --shell "$wid")"
    drag $((3 * WIDTH / 4)) $((HEIGHT / 2)) $((3 * WIDTH / 4 + 40)) $((HEIGHT / 2))
    read -r new_a _ new_b _ < <(sides)
    [ "$new_a" -lt "$spp_a" ] && [ "$new_b" -lt "$spp_b" ] || fail "an orbit did not restart the finished comparison"
    wait_title " — finished$"
elif [ "$mode" = truth ]; then
    # A resize restarts at 1000x700: its previews (the coarsest in a few ms), then the finest until
    # the average has 11 spp. Every title read while a preview is on screen shows no error, RMSE or
    # convergence, and before the run's first pass ("pass 0") no time left or rate either: nothing
    # is measured yet (they used to read "error 0.00 %", "RMSE 0" and "~12976712658183 s left");
    # once the average is on screen its figures show. 0.1 s apart, for 1.5 s.
    wait_title "bunny.scene — 800x600 — .* — error [0-9.]+ % — .* Mrays/s — pass [0-9]+ — .* RMSE [0-9.e-]+"
    xdotool windowsize "$wid" 1000 700
    previews=0
    for _ in $(seq 15); do
        t=$(title)
        if [[ $t == *" preview, "* || $t == *" — pass 0 — "* ]]; then
            previews=$((previews + 1))
            [[ $t =~ error\ [0-9]|RMSE\ [0-9]|converged ]] && fail "a figure of the average on a preview: $t"
            [[ $t == *" — pass 0 — "* && $t =~ \ s\ left|Mrays/s ]] && fail "a figure before the first pass: $t"
        fi
        sleep 0.1
    done
    echo "titles with a preview on screen: $previews of 15"
    [ "$previews" -ge 1 ] || fail "no title read while the preview was on screen"
    wait_title "bunny.scene — 1000x700 — .* — error [0-9.]+ % — .* Mrays/s — pass [0-9]+ — "
    press Escape
    wait "$pid" || fail "exit status $? after Esc"

    # E before any tile has an estimate (both halves of a tile need a pass, and --spp 1 runs one):
    # every tile "not known", a grey (0.2 linear, code 124) that S saves as displayed; the lowest
    # colour of the scale, dark blue, is what it used to paint (labelled 0.01 %).
    open_viewer "--spp 1" --size 320x240 --spp 1 --threads 2 "$scene"
    wait_title " — mean 1 spp, up to 1 — error — .* — finished — .* — pass 1 — "
    press e
    sleep 0.5
    press s
    check_screenshot 1 320 240
    read -r colours coloured < <(png_stats "$work/aoview-1.png")
    echo "E before an estimate: $colours colour(s), coloured share $coloured"
    [ "$colours" -eq 1 ] && [ "$coloured" = 0.0 ] || fail "E before an estimate did not paint every tile not known"
    press Escape
    wait "$pid" || fail "exit status $? after Esc"

    # A --size the 1280x1024 screen cannot hold: one line on stderr, the window at 90 % of the
    # screen and the image following it.
    open_viewer 1600x1200 --size 1600x1200 --spp 1000000 --threads 2 "$scene"
    wait_title "bunny.scene — 1152x864[ ,]"
    lines=$(grep -c "a 1600x1200 window does not fit 90 % of the 1280x1024 screen: it opens at 1152x864" stderr)
    [ "$lines" -eq 1 ] || fail "$lines lines about the --size that does not fit"
    press Escape
    wait "$pid" || fail "exit status $? after Esc"

    # The chart keeps every pass of a run over faster than the window presents: 64 one-sample
    # passes of the spheres at 160x120 (the window shows them 4 times magnified: no restart), over
    # in some tens of ms, charted as a curve across the plot in the sampling mode's colour, not as
    # the single point of the newest frame: the hemisphere colour's pixels against a run whose
    # curve is in cosine's (nothing of hemisphere's there: the legend names the runs made).
    spheres=$AO_SOURCE_ROOT/assets/scenes/spheres.scene
    "$AO_BINARY" --headless -q --size 160x120 --spp 64 --spppp 64 -o spheres.pfm "$spheres" || fail "no reference"
    for sampling in hemisphere cosine; do
        open_viewer "the chart" --size 160x120 --spp 64 --spppp 1 --threads 2 --adaptive off --sampling $sampling \
            --reference spheres.pfm "$spheres"
        wait_title "spheres.scene — 160x120 — $sampling — AA on — mean 64 spp, up to 64 — .* finished — .* RMSE [0-9.e-]+"
        sleep 0.5
        read -r _ green _ < <(chart_colours)
        [ "$sampling" = hemisphere ] && curve=$green || legend=$green
        press Escape
        wait "$pid" || fail "exit status $? after Esc"
    done
    echo "hemisphere-coloured chart pixels: $curve with the first run's curve, $legend with a cosine run"
    [ $((curve - legend)) -ge 30 ] || fail "the chart lost passes the window did not present"

    # --pixel-size auto on a HiDPI screen: X gives the content scale by Xft.dpi (192: 2), not by
    # the framebuffer, which is the window's size; the 640x480 window renders 320x240.
    xprop -root -f RESOURCE_MANAGER 8s -set RESOURCE_MANAGER "$(printf 'Xft.dpi:\t192\n')"
    open_viewer "Xft.dpi 192" --size 640x480 --spp 1000000 --threads 2 "$scene"
    wait_title "bunny.scene — 320x240 — "
    press Escape
    wait "$pid" || fail "exit status $? after Esc"
    echo "PASS (truth)"
    exit 0
elif [ "$mode" = resize ]; then
    # Each run's first pass is a --stats row with pass 1.
    runs() { awk -F, '$1 == 1' stats.csv | wc -l; }
    wait_title "spheres.scene — 640x480 — "
    [ "$(runs)" -eq 1 ] || fail "the window restarted the render before any resize ($(runs) runs)"
    xdotool windowsize "$wid" 500 400
    wait_title "spheres.scene — 500x400 — "
    sleep 0.5
    press s
    check_screenshot 1 500 400
    [ "$(runs)" -eq 2 ] || fail "a resize did not restart exactly once ($(runs) runs)"
    # ]: pixels of 2x2, half the size each way; [: back.
    press bracketright
    wait_title "spheres.scene — 250x200 — "
    sleep 0.5
    press s
    check_screenshot 2 250 200
    press bracketleft
    wait_title "spheres.scene — 500x400 — "
    [ "$(runs)" -eq 4 ] || fail "[ and ] did not restart once each ($(runs) runs)"
    # V, then a resize: both sides restart at the new size; side by side, the screenshot is two
    # 600x300 images.
    press v
    wait_title " — compare — A: "
    xdotool windowsize "$wid" 600 300
    sleep 1
    press b
    sleep 0.5
    press s
    check_screenshot 3 1200 300
    press Escape
    wait "$pid" || fail "exit status $? after Esc"
    # --pixel-size 2: the 640x480 window renders 320x240.
    "$AO_BINARY" --size 640x480 --pixel-size 2 --spp 1000000 --threads 2 "$scene" >stdout 2>stderr &
    pid=$!
    wid=$(timeout 20 xdotool search --sync --onlyvisible --name '^aoview') || fail "no window for --pixel-size 2"
    wid=${wid%%$'\n'*}
    wait_title "spheres.scene — 320x240 — "
    press s
    check_screenshot 4 320 240
else
    # Random keys (no S, Q or Esc), drags, wheel steps and resizes, as fast as xdotool goes.
    keys=(u h c a n f d e g v b space r plus minus equal KP_Add KP_Subtract F1 F2 question)
    RANDOM=1
    for i in $(seq 200); do
        case $((RANDOM % 4)) in
        0) xdotool windowsize "$wid" $((50 + RANDOM % 600)) $((50 + RANDOM % 500)) ;;
        1) button=$((RANDOM % 2 * 2 + 1))   # left or right
           xdotool mousemove --window "$wid" $((RANDOM % 100)) $((RANDOM % 100)) mousedown $button \
               mousemove_relative -- $((RANDOM % 41 - 20)) $((RANDOM % 41 - 20)) mouseup $button \
               click $((RANDOM % 2 + 4)) ;;   # wheel up or down
        *) press "${keys[RANDOM % ${#keys[@]}]}" ;;
        esac
        kill -0 "$pid" 2>/dev/null || fail "aoview died after $i random inputs"
    done
    # Release any button a drag above left down; then the viewer must still answer, with a
    # screenshot at the size the title gives once the last resize has taken.
    # Every input sent has been handled once a pause toggled after them shows in the title (X
    # delivers events in order; under TSan the viewer drains the 200 inputs seconds after xdotool
    # sent them, so a resize could still come between reading the title and saving). It ends
    # resumed: a restart while paused can leave a preview on screen, and S saves full frames only.
    # The last resize has then taken once the title's size holds for a second (a resize restarts
    # 0.15 s after its last event).
    xdotool mouseup 1 mouseup 3 2>/dev/null
    paused() { [[ $(title) == *" — paused" ]]; }
    for _ in 1 2; do
        if paused; then was=0; else was=1; fi
        press space
        for _ in $(seq 400); do
            if paused; then now=0; else now=1; fi
            [ "$now" != "$was" ] && break
            sleep 0.05
        done
        [ "$now" != "$was" ] || fail "Space never toggled the pause in the title"
        paused || break
    done
    size="" held=0
    for _ in $(seq 100); do
        now=""
        [[ $(title) =~ spheres.scene\ —\ ([0-9]+x[0-9]+)\ — ]] && now=${BASH_REMATCH[1]}
        if [ -n "$now" ] && [ "$now" = "$size" ]; then held=$((held + 1)); else held=0 size=$now; fi
        [ "$held" -ge 5 ] && break
        sleep 0.2
    done
    [ "$held" -ge 5 ] || fail "the size in the title never held for a second"
    wait_title "spheres.scene — [0-9]+x[0-9]+ — "
    [[ $(title) =~ spheres.scene\ —\ ([0-9]+)x([0-9]+)\ — ]] || fail "no size in the title"
    press s
    check_screenshot 1 "${BASH_REMATCH[1]}" "${BASH_REMATCH[2]}"
fi

# Esc: the process ends, with status 0, within a second even with a pass in flight.
press Escape
for _ in $(seq 100); do
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.01
done
kill -0 "$pid" 2>/dev/null && fail "still running 1 s after Esc"
wait "$pid"
status=$?
[ "$status" -eq 0 ] || fail "exit status $status after Esc"
echo "PASS ($mode)"
