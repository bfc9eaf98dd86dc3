#!/usr/bin/env bash
# The file formats end to end. The bunny as binary and ASCII STL, glTF with an external and with
# an embedded buffer, and GLB (tests/mesh_convert.py; the glTF files nest two transforms that
# cancel) renders as the bunny OBJ does, bare and through a scene's mesh line: same seed and
# settings, so the images differ only where float rounding of the transformed positions moves a
# hit, and the mean absolute difference must stay within 0.2 % of the mean. EXR output carries the
# settings in its header (checked with exrheader when installed) and reads back as a --reference
# with RMSE exactly 0; a failed EXR write leaves no file.
set -u
bin=${AO_BINARY:?AO_BINARY not set}
root=${AO_SOURCE_ROOT:?AO_SOURCE_ROOT not set}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

# compare A B: mean |A - B| over all pixels and channels of two PFMs, relative to A's mean.
compare() {
  python3 - "$1" "$2" <<'PY'
import struct, sys
def read(path):
    data = open(path, 'rb').read()
    head = data.split(b'\n', 3)
    w, h = map(int, head[1].split())
    return struct.unpack('<%df' % (3 * w * h), head[3])
a, b = read(sys.argv[1]), read(sys.argv[2])
assert len(a) == len(b), 'sizes differ'
diff = sum(abs(x - y) for x, y in zip(a, b)) / len(a) / (sum(a) / len(a))
print('%.4f %%' % (100 * diff))
sys.exit(0 if diff <= 0.002 else 1)
PY
}

render() { "$bin" --headless -q --size 96x72 --spp 16 --spppp 4 --seed 3 "$@"; }

obj=$root/assets/bunny.obj
convert=$root/tests/mesh_convert.py
python3 "$convert" "$obj" binary.stl && python3 "$convert" "$obj" ascii.stl --ascii &&
  python3 "$convert" "$obj" external.gltf && python3 "$convert" "$obj" embedded.gltf --embed &&
  python3 "$convert" "$obj" bunny.glb || fail "mesh_convert.py failed"
cp "$obj" bunny.obj
render bunny.obj -o obj.pfm || fail "the OBJ did not render"
{
  echo 'camera eye 0.5 1 2.5 target 0 0.42 0 up 0 1 0 fov 35'
  echo 'mesh bunny.obj scale 0.1'
  echo 'quad corner -50 0 -50 edge1 0 0 100 edge2 100 0 0'
} > obj.scene
render obj.scene -o obj-scene.pfm || fail "the OBJ scene did not render"
for mesh in binary.stl ascii.stl external.gltf embedded.gltf bunny.glb; do
  if ! render "$mesh" -o "$mesh.pfm"; then
    fail "$mesh did not render"
  elif ! got=$(compare obj.pfm "$mesh.pfm"); then
    fail "$mesh differs from the OBJ by $got"
  else
    echo "$mesh renders as the OBJ (mean difference $got)"
  fi
  sed "s/bunny.obj/$mesh/" obj.scene > "$mesh.scene"
  if ! render "$mesh.scene" -o "$mesh-scene.pfm"; then
    fail "$mesh in a scene did not render"
  elif ! got=$(compare obj-scene.pfm "$mesh-scene.pfm"); then
    fail "$mesh in a scene differs from the OBJ by $got"
  fi
done

# More than 65536 vertices: 32-bit indices in the glTF buffer.
python3 "$convert" --grid 260 grid.obj && python3 "$convert" grid.obj grid.glb || fail "no grid"
render grid.obj -o grid-obj.pfm && render grid.glb -o grid-glb.pfm || fail "the grid did not render"
got=$(compare grid-obj.pfm grid-glb.pfm) || fail "the grid as GLB differs from the OBJ by $got"

# EXR out, its header, and back in as a reference.
spheres=$root/assets/scenes/spheres.scene
render "$spheres" -o out.exr --sampling hemisphere || fail "-o out.exr failed"
if command -v exrheader >/dev/null; then
  header=$(exrheader out.exr)
  for line in 'aoview.spp (type string): "16"' 'aoview.sampling (type string): "hemisphere"' \
              'aoview.seed (type string): "3"' 'R, 32-bit floating-point' \
              'B, 32-bit floating-point'; do
    grep -qF "$line" <<<"$header" || fail "out.exr's header lacks '$line'"
  done
else
  echo "exrheader (Debian package openexr) not installed: header not checked"
fi
render "$spheres" --sampling hemisphere --stats stats.csv --reference out.exr -o again.pfm ||
  fail "--reference out.exr failed"
[ "$(tail -n 1 stats.csv | cut -d, -f7)" = 0 ] ||
  fail "the same render differs from its EXR: $(tail -n 1 stats.csv)"
render "$spheres" -o missing/out.exr 2>err.txt && fail "-o into a missing directory succeeded"
[ "$(wc -l < err.txt)" = 1 ] || fail "a failed EXR write printed: $(cat err.txt)"
[ -z "$(ls missing 2>/dev/null)" ] || fail "a failed EXR write left a file"

echo "$failures failure(s)"
[ "$failures" = 0 ]
