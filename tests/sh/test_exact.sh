#!/usr/bin/env bash
# aoview-exact against aoview: identical images where the estimator is exact (cosine sampling on an
# open plane gives rho per sample, a closed box 0), the whole analytic image's mean error within
# 4 predicted standard errors for every sampler, and one-line refusals of scenes without a closed form.
. "$(dirname "$0")/lib.sh"
exact=${AO_EXACT:?AO_EXACT not set}
scenes=$root/assets/scenes

# Exact estimators: the same bytes.
for scene in open-plane closed-box; do
  "$exact" -q --no-aa --size 40x30 -o "$scene-exact.pfm" "$scenes/$scene.scene" || fail "$scene: aoview-exact failed"
  "$bin" --headless -q --no-aa --size 40x30 --spp 64 --spppp 16 -o "$scene.pfm" "$scenes/$scene.scene" ||
    fail "$scene: aoview failed"
  cmp -s "$scene.pfm" "$scene-exact.pfm" || fail "$scene: aoview differs from the exact image"
done

# Unbiased estimators: the mean error over the image, per sampler, with AA against the box-filtered
# exact image. Pixels are independent (their own random streams), so the mean of the per-pixel
# errors of two seeds has standard error sqrt(sum of per-pixel variances / 2) / pixels, each
# variance estimated from the two seeds as (a - b)^2 / 2; the exact image's sub-pixel residual
# (below 1e-5 on the image mean at this grid, docs/accuracy.md) is far below it. Bound: 4 of those.
# The same scene a million units from the origin (every coordinate shifted by 1e6), which the
# scene stores about its own centre: aoview-exact's image matches the one at the origin (the two
# local frames round differently, so a sub-pixel cell may flip between sphere and ground at an
# edge: one of 4096 cells changes a pixel by at most 1/4096, as values and background lie in
# [0, 1]; allow four), and
# aoview stays unbiased against it.
python3 - "$scenes/sphere-on-plane.scene" far.scene <<'PY'
import sys
points = {'eye', 'target', 'corner', 'center'}
out = []
for line in open(sys.argv[1]):
    tokens = line.split('#')[0].split()
    for i, t in enumerate(tokens):
        if t in points:
            for k in range(1, 4):
                tokens[i + k] = repr(float(tokens[i + k]) + 1e6)
    out.append(' '.join(tokens))
open(sys.argv[2], 'w').write('\n'.join(out) + '\n')
PY
"$exact" -q --size 64x48 --spp 4096 -o sphere-exact.pfm "$scenes/sphere-on-plane.scene" || fail "sphere: aoview-exact failed"
"$exact" -q --size 64x48 --spp 4096 -o far-exact.pfm far.scene || fail "far sphere: aoview-exact failed"
python3 - sphere-exact.pfm far-exact.pfm <<'PY' || fail "far sphere: aoview-exact differs from the scene at the origin"
import struct, sys
def read(path):
    parts = open(path, 'rb').read().split(b'\n', 3)
    w, h = map(int, parts[1].split())
    return struct.unpack('<%df' % (3 * w * h), parts[3])
near, far = (read(p) for p in sys.argv[1:])
worst = max(abs(a - b) for a, b in zip(near, far))
print('sphere-on-plane at 1e6 against the origin, exact images: largest difference %.2e' % worst)
sys.exit(0 if worst <= 4 / 4096 else 1)
PY
for case in sphere-uniform sphere-hemisphere sphere-cosine far-cosine; do
  sampling=${case#*-}
  scene=$scenes/sphere-on-plane.scene
  [ "${case%%-*}" = far ] && scene=far.scene
  for seed in 1 2; do
    "$bin" --headless -q --size 64x48 --spp 256 --spppp 64 --sampler random --adaptive off --sampling "$sampling" --seed "$seed" \
      -o "$case-$seed.pfm" "$scene" || fail "$case: aoview failed"
  done
  python3 - "$case" "${case%%-*}-exact.pfm" "$case-1.pfm" "$case-2.pfm" <<'PY' || fail "$case: biased"
import math, struct, sys
def read(path):
    parts = open(path, 'rb').read().split(b'\n', 3)
    w, h = map(int, parts[1].split())
    v = struct.unpack('<%df' % (3 * w * h), parts[3])
    return [sum(v[k:k + 3]) / 3 for k in range(0, len(v), 3)]
ref, a, b = (read(p) for p in sys.argv[2:])
n = len(ref)
mean = sum((x + y) / 2 - r for x, y, r in zip(a, b, ref)) / n
se = math.sqrt(sum((x - y) ** 2 / 2 for x, y in zip(a, b)) / 2) / n
print('%s: mean error %+.2e, standard error %.2e (%+.2f)' % (sys.argv[1], mean, se, mean / se))
sys.exit(0 if abs(mean) <= 4 * se else 1)
PY
done

# Adaptive sampling stops pixels on their own error estimate, which could bias them (a tile whose
# samples happened to agree stops early). Two seeds of an adaptive run to --target-error 0.01:
# the mean error over the image against the exact image within 4 standard errors, estimated per
# pixel from the two seeds as above (each pixel's two estimates are independent whatever spp each
# seed stopped at). And the estimate itself: the run's last --stats row's estimated relative error
# within a factor 1.25 of the true one (the RMSE against the exact image over its mean).
for sampler in random sobol; do
  for seed in 1 2; do
    "$bin" --headless -q --size 64x48 --spp 4096 --spppp auto --adaptive on --target-error 0.01 \
      --sampler "$sampler" --seed "$seed" --reference sphere-exact.pfm --stats "adaptive-$sampler-$seed.csv" \
      -o "adaptive-$sampler-$seed.pfm" "$scenes/sphere-on-plane.scene" || fail "sphere: adaptive $sampler failed"
  done
  python3 - "$sampler" sphere-exact.pfm "adaptive-$sampler-1.pfm" "adaptive-$sampler-2.pfm" \
    "adaptive-$sampler-1.csv" "adaptive-$sampler-2.csv" <<'PY' || fail "sphere: adaptive $sampler is biased or misjudges its error"
import csv, math, struct, sys
def read(path):
    parts = open(path, 'rb').read().split(b'\n', 3)
    w, h = map(int, parts[1].split())
    v = struct.unpack('<%df' % (3 * w * h), parts[3])
    return [sum(v[k:k + 3]) / 3 for k in range(0, len(v), 3)]
ref, a, b = (read(p) for p in sys.argv[2:4 + 1])
n = len(ref)
mean = sum((x + y) / 2 - r for x, y, r in zip(a, b, ref)) / n
se = math.sqrt(sum((x - y) ** 2 / 2 for x, y in zip(a, b)) / 2) / n
ok = abs(mean) <= 4 * se
image_mean = sum(ref) / n
for path in sys.argv[5:]:
    last = list(csv.DictReader(open(path)))[-1]
    true = float(last['rmse']) / image_mean
    ratio = float(last['error']) / true
    print('%s: %s stops at mean %s spp, estimate %.4f, true %.4f (x%.2f)' % (sys.argv[1], path, last['mean_spp'],
          float(last['error']), true, ratio))
    ok = ok and 1 / 1.25 <= ratio <= 1.25 and float(last['error']) <= 0.01
print('%s: mean error %+.2e, standard error %.2e (%+.2f)' % (sys.argv[1], mean, se, mean / se))
sys.exit(0 if ok else 1)
PY
done

# Refusals: exit 1, one line naming the scene, no output.
for scene in spheres bunny; do
  "$exact" -o refused.pfm "$scenes/$scene.scene" 2>err.txt
  status=$?
  [ $status -eq 1 ] || fail "$scene: exit status $status, expected 1"
  [ "$(wc -l <err.txt)" -eq 1 ] && grep -q "$scene.scene: no closed form" err.txt || fail "$scene: message: $(cat err.txt)"
  [ ! -e refused.pfm ] || fail "$scene: wrote an image"
done
"$exact" -q -o x.png "$scenes/open-plane.scene" 2>/dev/null
[ $? -eq 2 ] || fail "a .png output is not a usage error"

# -o is checked as aoview checks it (the same functions): not the scene, through a link or by name,
# nor a file the scene reads (a mesh, through a link), each refused in one line before writing,
# the input left as it was.
cp "$scenes/open-plane.scene" own.scene
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' > tri.obj
printf 'camera eye 0 1 4 target 0 0 0\nmesh tri.obj translate 0 1 0\nquad corner -5 0 -5 edge1 0 0 10 edge2 10 0 0\n' \
  > meshed.scene
ln -s own.scene scene-link.pfm
ln -s tri.obj mesh-link.pfm
for case in "scene-link.pfm own.scene:-o: scene-link.pfm is also the scene (own.scene): aoview does not overwrite its inputs" \
            "mesh-link.pfm meshed.scene:-o: mesh-link.pfm is a file the scene reads (tri.obj): aoview does not overwrite its inputs"; do
  args=${case%%:*} want=${case#*:}
  cp own.scene own.before && cp tri.obj tri.before
  # shellcheck disable=SC2086 # two words
  "$exact" -q --size 8x6 -o $args 2>err.txt
  status=$?
  [ $status -eq 1 ] && [ "$(cat err.txt)" = "$want" ] || fail "aoview-exact -o $args: status $status: $(cat err.txt)"
  cmp -s own.scene own.before && cmp -s tri.obj tri.before || fail "aoview-exact -o $args overwrote its input"
done

[ $failures -eq 0 ] && echo "all passed"
finish
