#!/usr/bin/env bash
# End to end: the built binary on both shipped scenes and on bad input. Every bad input must give
# exit status 1 (runtime) or 2 (usage), exactly one line on stderr naming the culprit, and no
# output file.
. "$(dirname "$0")/lib.sh"

# pfm_check FILE W H: a well-formed PFM of that size with only finite, non-negative values.
pfm_check() {
  python3 - "$@" <<'PY'
import math, struct, sys
path, w, h = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
data = open(path, 'rb').read()
parts = data.split(b'\n', 3)
assert parts[0] == b'PF', 'magic'
assert parts[1].split() == [str(w).encode(), str(h).encode()], 'size'
assert float(parts[2]) < 0, 'little endian'
values = struct.unpack('<%df' % (3 * w * h), parts[3])
assert all(math.isfinite(v) and v >= 0 for v in values), 'non-finite or negative pixel'
PY
}

# Good runs: both scenes, PNG and PFM, stats and reference.
for scene in bunny spheres; do
  if ! "$bin" --headless -q --size 64x48 --spp 8 --spppp 4 "$root/assets/scenes/$scene.scene" -o "$scene.pfm"; then
    fail "$scene.scene did not render"
  elif ! pfm_check "$scene.pfm" 64 48; then
    fail "$scene.pfm is not a clean 64x48 PFM"
  fi
  "$bin" --headless -q --size 64x48 --spp 4 "$root/assets/scenes/$scene.scene" -o "$scene.png" ||
    fail "$scene.scene did not render to PNG"
  [ "$(head -c 8 "$scene.png" | od -An -tx1 | tr -d ' ')" = 89504e470d0a1a0a ] || fail "$scene.png is not a PNG"
done

"$bin" --headless -q --size 32x24 --spp 10 --spppp 4 --stats stats.csv --reference bunny.pfm.ref \
  "$root/assets/scenes/bunny.scene" -o x.pfm 2>/dev/null && fail "a missing --reference was accepted"
"$bin" --headless -q --size 32x24 --spp 64 --spppp 64 "$root/assets/scenes/bunny.scene" -o ref.pfm
# An existing, longer stats.csv: opened without truncating (so that a run that finishes no pass
# leaves it alone), it must be emptied at the first row, not overwritten in place.
python3 -c "open('stats.csv', 'w').write('old row\n' * 1000)"
"$bin" --headless -q --size 32x24 --spp 10 --spppp 4 --adaptive off --stats stats.csv --reference ref.pfm \
  "$root/assets/scenes/bunny.scene" -o x.pfm || fail "stats run failed"
python3 - <<'PY' || fail "stats.csv is malformed"
import csv
rows = list(csv.reader(open('stats.csv')))
assert rows[0] == ['pass', 'spp', 'seconds', 'eye_rays', 'shadow_rays', 'mrays_per_s', 'rmse', 'mean_spp',
                   'error', 'converged'], rows[0]
body = rows[1:]
assert [int(r[0]) for r in body] == [1, 2, 3], 'passes = ceil(10 / 4)'
assert [int(r[1]) for r in body] == [4, 8, 10], 'cumulative spp'
assert [int(r[3]) for r in body] == [768, 1536, 2304], 'one eye ray per pixel per pass'
assert all(float(r[6]) > 0 for r in body), 'rmse'
assert [float(r[7]) for r in body] == [4, 8, 10], 'mean spp without adaptive sampling'
assert body[0][8] == 'nan' and all(float(r[8]) > 0 for r in body[1:]), 'error estimate from the second pass on'
assert all(float(r[9]) == 0 for r in body), 'nothing converged without adaptive sampling'
PY

# A --stats file that cannot be written: one line and status 1, also when it is a FIFO whose
# reader has left (the write then fails with EPIPE instead of SIGPIPE killing aoview).
"$bin" --headless -q --size 16x12 --spp 2 --stats /dev/full "$root/assets/scenes/spheres.scene" -o full.png \
  2>err.txt
status=$?
[ "$status" = 1 ] || fail "--stats /dev/full exited $status, expected 1"
[ "$(cat err.txt)" = "/dev/full: write failed" ] || fail "--stats /dev/full: $(cat err.txt)"
# A file this run creates on a full disk (a file size limit of 0: every write to a regular file
# fails, as on a full disk, with EFBIG where SIGXFSZ is ignored): the same line, and no empty
# CSV left behind (the -o file, the same way, is not written either).
rm -f full.csv full.pfm
(trap '' XFSZ; ulimit -f 0; exec "$bin" --headless -q --size 16x12 --spp 2 --stats full.csv -o full.pfm \
  "$root/assets/scenes/spheres.scene") 2>&1 | cat > err.txt
status=${PIPESTATUS[0]}
[ "$status" = 1 ] || fail "--stats onto a full disk exited $status, expected 1"
grep -qx "full.csv: write failed" err.txt || fail "--stats onto a full disk: $(cat err.txt)"
[ ! -e full.csv ] || fail "--stats onto a full disk left the file it created ($(wc -c < full.csv) bytes)"
# The reader leaves after the header; a row per pass follows, 5000 of them, so that later ones
# find the pipe closed however the two processes are scheduled.
mkfifo stats.fifo
head -c 10 stats.fifo >/dev/null &
timeout 60 "$bin" --headless -q --size 32x24 --spp 5000 --stats stats.fifo "$root/assets/scenes/spheres.scene" \
  -o fifo.png 2>err.txt
status=$?
[ "$status" = 1 ] || fail "--stats to a FIFO whose reader left exited $status, expected 1"
[ "$(cat err.txt)" = "stats.fifo: write failed" ] || fail "--stats to a FIFO whose reader left: $(cat err.txt)"

# The same seed and settings give the same image for any thread count.
"$bin" --headless -q --size 40x30 --spp 6 --spppp 2 --threads 1 --seed 9 "$root/assets/scenes/spheres.scene" -o t1.pfm
"$bin" --headless -q --size 40x30 --spp 6 --spppp 2 --threads 2 --seed 9 "$root/assets/scenes/spheres.scene" -o t2.pfm
cmp -s t1.pfm t2.pfm || fail "--threads 1 and 2 differ"

# Views: --view difference writes the heat map as PNG and keeps the PFM the linear AO image, the
# very one a plain run makes; --view normals and --shading flat render; --time ends a run that
# --spp alone would keep going for hours.
diff_args=(--headless -q --size 32x24 --spp 8 --spppp 4 "$root/assets/scenes/bunny.scene")
"$bin" "${diff_args[@]}" --view difference --reference ref.pfm -o diff.png || fail "--view difference failed"
[ "$(head -c 8 diff.png 2>/dev/null | od -An -tx1 | tr -d ' ')" = 89504e470d0a1a0a ] || fail "diff.png is not a PNG"
"$bin" "${diff_args[@]}" -o plain.png && cmp -s plain.png diff.png && fail "--view difference wrote the AO image"
"$bin" "${diff_args[@]}" --view difference --reference ref.pfm -o diff.pfm || fail "--view difference to PFM failed"
"$bin" "${diff_args[@]}" -o plain.pfm && cmp -s plain.pfm diff.pfm || fail "--view difference changed the PFM"
"$bin" "${diff_args[@]}" --view normals --shading flat -o normals.pfm && pfm_check normals.pfm 32 24 ||
  fail "--view normals --shading flat failed"
cmp -s plain.pfm normals.pfm && fail "--view normals wrote the AO image"
start=$SECONDS
"$bin" --headless -q --size 32x24 --spp 100000000 --time 0.5 "$root/assets/scenes/spheres.scene" -o timed.pfm ||
  fail "--time run failed"
[ $((SECONDS - start)) -le 20 ] || fail "--time 0.5 took $((SECONDS - start)) s"
pfm_check timed.pfm 32 24 || fail "timed.pfm is not a clean 32x24 PFM"

# Bad input: expect_error STATUS TEXT ARGS...
expect_error() {
  local want=$1 text=$2
  shift 2
  rm -f out.png
  "$bin" --headless -q -o out.png "$@" 2>err.txt >/dev/null
  local got=$?
  if [ "$got" != "$want" ]; then fail "$* exited $got, expected $want"; fi
  if [ "$(wc -l < err.txt)" != 1 ]; then fail "$*: expected one stderr line, got: $(cat err.txt)"; fi
  grep -qF -- "$text" err.txt || fail "$*: message lacks '$text': $(cat err.txt)"
  [ -e out.png ] && fail "$*: left an output file"
  ls out.png.tmp* >/dev/null 2>&1 && fail "$*: left a temporary file"
  return 0
}

expect_error 2 --spp --spp 0
expect_error 2 --size --size 0x5
expect_error 2 --size --size 100000x100000
expect_error 2 --sampling --sampling foo
expect_error 2 --bogus --bogus
expect_error 2 "--view difference: needs --reference" --view difference
expect_error 2 --view --view depth
expect_error 2 --shading --shading smooth
expect_error 2 --time --time 0
expect_error 2 --time --time -3
expect_error 1 nowhere.scene nowhere.scene
rm -f new.csv
expect_error 1 nowhere.scene --stats new.csv nowhere.scene
[ -e new.csv ] && fail "a run that failed to load left the --stats file it created"
expect_error 1 "$root/assets" "$root/assets"
printf 'camera eye 0 1 4 target 0 0 0\nsphere center 0 0 0 radius -1\n' > neg.scene
expect_error 1 neg.scene:2: neg.scene
printf 'camera eye 0 1 4 target 0 0 0\nsphere center 0 nan 0 radius 1\n' > nan.scene
expect_error 1 nan.scene:2: nan.scene
printf 'camera eye 0 1 4 target 0 0 0\nteapot\n' > kw.scene
expect_error 1 kw.scene:2: kw.scene
printf 'camera eye 0 1 4 target 0 0 0 colour 3\n' > key.scene
expect_error 1 key.scene:1: key.scene
printf 'camera eye 0 1 4 target 0 0\n' > short.scene
expect_error 1 short.scene:1: short.scene
printf 'camera eye 0 1 4 target 0 1 4\n' > degenerate.scene
expect_error 1 degenerate.scene:1: degenerate.scene
printf 'quad corner 0 0 0 edge1 1 0 0 edge2 2 0 0\n' > flat.scene
expect_error 1 flat.scene:1: flat.scene
printf 'mesh missing.obj\n' > mesh.scene
expect_error 1 missing.obj mesh.scene
printf 'sphere center 0 0 0 radius 1 albedo 1.5\n' > albedo.scene
expect_error 1 albedo.scene:1: albedo.scene
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n' > bad.obj
expect_error 1 bad.obj:4: bad.obj
printf 'ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\1\2' > truncated.ply
expect_error 1 truncated.ply truncated.ply

echo "$failures failure(s)"
finish
