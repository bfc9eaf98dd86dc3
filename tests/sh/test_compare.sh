#!/usr/bin/env bash
# --compare A,B --headless end to end: one PNG twice the width whose halves are the two renders
# with a label burnt in at the top, per-side stats rows, equal render time within 5 %, a linear
# file per side, one line with status 2 for every malformed configuration, and the window's
# comparison where no display exists: one line saying so, then the same headless output.
. "$(dirname "$0")/lib.sh"
scene="$root/assets/scenes/bunny.scene"

# Small fixed passes (160x60 pixels x 8 spp = 76,800 samples, a few ms even on a loaded machine)
# and no adaptive sampling, so that a side's image is a function of its spp alone; 160 pixels
# wide so that a label fits its side.
args=(--headless -q --size 160x60 --spppp 8 --adaptive off "$scene")

"$bin" "${args[@]}" --compare uniform,cosine --time 1 --stats c.csv -o c.png || fail "--compare to PNG failed"

# Fairness: each side ends at the pass end nearest 1 s, so within half a pass of it and the two
# within one pass (under 0.02 s at 5 Mrays/s, a tenth of what this machine does unloaded) of
# each other: 5 % of 1 s leaves room for a pass slowed twofold by other work.
python3 - <<'PY' || fail "stats of --compare are not per side, or the sides' times differ by more than 5 %"
import csv
rows = list(csv.reader(open('c.csv')))
assert rows[0][:3] == ['side', 'pass', 'spp'], rows[0]
last = {}
for r in rows[1:]:
    assert r[0] in ('A', 'B'), r
    last[r[0]] = r
a, b = float(last['A'][3]), float(last['B'][3])
print('seconds A %.3f B %.3f spp A %s B %s' % (a, b, last['A'][2], last['B'][2]))
assert abs(a - b) <= 0.05 * max(a, b), (a, b)
assert abs(a - 1.0) <= 0.05 and abs(b - 1.0) <= 0.05, (a, b)
open('spp_a', 'w').write(last['A'][2])
PY

# The left half is side A: the same image as a plain uniform render of A's spp below the label
# band, and not the same in it (the label is there). PNGs decoded with zlib alone.
"$bin" "${args[@]}" --sampling uniform --spp "$(cat spp_a 2>/dev/null || echo 16)" -o a.png || fail "plain render failed"
python3 - <<'PY' || fail "the --compare PNG is not 320x60 with side A labelled on its left half"
import struct, zlib
def read(path):
    data = open(path, 'rb').read()
    assert data[:8] == b'\x89PNG\r\n\x1a\n'
    pos, idat = 8, b''
    while pos < len(data):
        n, kind = struct.unpack('>I4s', data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b'IHDR':
            w, h, depth, colour = struct.unpack('>IIBB', body[:10])
            assert depth == 8 and colour in (2, 6)
            bpp = 3 if colour == 2 else 4
        elif kind == b'IDAT':
            idat += body
        pos += 12 + n
    raw, rows, prev, stride = zlib.decompress(idat), [], bytearray(w * bpp), w * bpp
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], prev[i - bpp] if i >= bpp else 0
            p = a + b - c
            pr = a if abs(p - a) <= abs(p - b) and abs(p - a) <= abs(p - c) else b if abs(p - b) <= abs(p - c) else c
            line[i] = (line[i] + [0, a, b, (a + b) // 2, pr][f]) & 255
        rows.append([tuple(line[x * bpp:x * bpp + 3]) for x in range(w)])
        prev = line
    return w, h, rows
cw, ch, c = read('c.png')
aw, ah, a = read('a.png')
assert (cw, ch) == (320, 60) and (aw, ah) == (160, 60), (cw, ch, aw, ah)
band = 40   # two lines of 12 pixels in a box from y = 4 with 4 pixels of padding: rows 4 to 35
assert all(c[y][:160] == a[y] for y in range(band, 60)), 'left half below the label is not side A'
assert sum(c[y][x] != a[y][x] for y in range(band) for x in range(160)) > 500, 'no label on side A'
assert sum(c[y][160 + x] != c[y][x] for y in range(band, 60) for x in range(160)) > 0, 'both halves alike'
PY

# A linear file per side, named after -o, and no file under -o's own name.
"$bin" "${args[@]}" --compare cosine+random,cosine+sobol --time 0.3 -o c.pfm || fail "--compare to PFM failed"
for side in A B; do
  [ "$(head -c 2 "c-$side.pfm" 2>/dev/null)" = PF ] && [ "$(sed -n 2p "c-$side.pfm")" = "160 60" ] ||
    fail "c-$side.pfm is not a 160x60 PFM"
done
[ -e c.pfm ] && fail "--compare wrote c.pfm as well"

# Bad configurations: one line, status 2, no file.
for bad in uniform a,b,c cosine+foo,cosine cosine+aa+noaa,uniform ,cosine; do
  "$bin" "${args[@]}" --compare "$bad" -o bad.png 2>err.txt
  status=$?
  [ "$status" = 2 ] && [ "$(wc -l <err.txt)" = 1 ] && [ ! -e bad.png ] ||
    fail "--compare $bad: status $status, $(wc -l <err.txt) lines"
done
# The window's comparison where no display exists: one line saying so, then the headless one.
env -u DISPLAY -u WAYLAND_DISPLAY "$bin" "${args[@]:1}" --compare uniform,cosine --time 0.2 -o window.png 2>err.txt
status=$?
[ "$status" = 0 ] && [ "$(wc -l <err.txt)" = 1 ] && grep -q "no display available; rendering headless to window.png" err.txt &&
  python3 -c "import struct, sys; d = open('window.png', 'rb').read(); sys.exit(struct.unpack('>II', d[16:24]) != (320, 60))" ||
  fail "--compare without a display: status $status, $(cat err.txt)"

[ "$failures" = 0 ] && echo "all compare checks passed"
finish
