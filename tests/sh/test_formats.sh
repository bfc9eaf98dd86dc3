#!/usr/bin/env bash
# The file formats end to end. The bunny as binary and ASCII STL, glTF with an external and with
# an embedded buffer, and GLB (tests/tools/mesh_convert.py; the glTF files nest two transforms that
# cancel) renders as the bunny OBJ does, bare and through a scene's mesh line: same seed and
# settings, so the images differ only where float rounding of the transformed positions moves a
# hit, and the mean absolute difference must stay within 0.2 % of the mean. None of them gives
# normals: STL's are made as OBJ's (smooth up to the crease angle), glTF's flat, as its
# specification says, which the OBJ gives with --crease-angle 0. Then the shapes of
# tests/tools/shapes.py, flat or smooth by construction, against their exact normals. Then glTF as exporters
# write it (strips, fans, sparse, quantized, meshopt and Draco; tests/gltf_encode for the last two),
# exactly or within Monte Carlo noise (below), and what aoview says of such files. EXR output carries the
# settings in its header (checked with exrheader when installed) and reads back as a --reference
# with RMSE exactly 0; a failed EXR write leaves no file.
. "$(dirname "$0")/lib.sh"

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
convert=$root/tests/tools/mesh_convert.py
python3 "$convert" "$obj" binary.stl && python3 "$convert" "$obj" ascii.stl --ascii &&
  python3 "$convert" "$obj" external.gltf && python3 "$convert" "$obj" embedded.gltf --embed &&
  python3 "$convert" "$obj" bunny.glb || fail "mesh_convert.py failed"
cp "$obj" bunny.obj
render bunny.obj -o obj.pfm && render bunny.obj --crease-angle 0 -o obj-flat.pfm || fail "the OBJ did not render"
{
  echo 'camera eye 0.5 1 2.5 target 0 0.42 0 up 0 1 0 fov 35'
  echo 'mesh bunny.obj scale 0.1'
  echo 'quad corner -50 0 -50 edge1 0 0 100 edge2 100 0 0'
} > obj.scene
render obj.scene -o obj-scene.pfm && render obj.scene --crease-angle 0 -o obj-flat-scene.pfm ||
  fail "the OBJ scene did not render"
for mesh in binary.stl ascii.stl external.gltf embedded.gltf bunny.glb; do
  like=obj; case $mesh in *.gltf|*.glb) like=obj-flat;; esac
  if ! render "$mesh" -o "$mesh.pfm"; then
    fail "$mesh did not render"
  elif ! got=$(compare $like.pfm "$mesh.pfm"); then
    fail "$mesh differs from the OBJ by $got"
  else
    echo "$mesh renders as the OBJ (mean difference $got)"
  fi
  sed "s/bunny.obj/$mesh/" obj.scene > "$mesh.scene"
  if ! render "$mesh.scene" -o "$mesh-scene.pfm"; then
    fail "$mesh in a scene did not render"
  elif ! got=$(compare $like-scene.pfm "$mesh-scene.pfm"); then
    fail "$mesh in a scene differs from the OBJ by $got"
  fi
done

# glTF as exporters write it. Exactly the flat OBJ's image where the decoded positions and triangles
# are exactly the OBJ's (corners in the same order: one strip joined by zero-area triangles, fans, a
# sparse accessor, meshopt attributes and index sequence, Draco's sequential coding without
# quantization): same seed, same samples, same pixels, compared byte for byte.
encode=${AO_GLTF_ENCODE:-}
if [ -z "$encode" ] || [ ! -x "$encode" ]; then
  fail "AO_GLTF_ENCODE (tests/gltf_encode) is not set: run through meson test"
  encode=false
fi
for form in strip fan sparse quantized quantized-packed; do
  python3 "$convert" "$obj" "$form.gltf" "--$form" || fail "mesh_convert.py --$form failed"
done
# The quantized shorts packed 6 bytes apart, off glTF's alignment and without KHR_mesh_quantization
# declared (cesium-native's cubeQuantized.glb's layout, which its reader loads): read as they lie,
# with one line saying so, into the image of the same shorts 8 bytes apart, bit for bit.
"$bin" --headless --size 96x72 --spp 4 quantized-packed.gltf -o packed.pfm 2>packed.err &&
  "$bin" --headless -q --size 96x72 --spp 4 quantized.gltf -o aligned.pfm || fail "the quantized forms did not render"
grep -qx "aoview: quantized-packed.gltf: accessor 0 (POSITION) at byte 0 of its buffer, 6 bytes apart, off glTF's alignment: read as it lies" packed.err ||
  fail "quantized-packed.gltf: no line saying it was read off its alignment: $(cat packed.err)"
cmp -s aligned.pfm packed.pfm || fail "the packed shorts render otherwise than the aligned ones: $(compare aligned.pfm packed.pfm)"
for form in meshopt meshopt-quantized draco draco-sequential draco-quantized draco-fewer; do
  "$encode" "$form" "$obj" "$form.glb" || fail "gltf_encode $form failed"
done
for mesh in strip.gltf fan.gltf sparse.gltf meshopt.glb draco-sequential.glb; do
  if ! render "$mesh" -o "$mesh.pfm"; then fail "$mesh did not render"
  elif ! cmp -s obj-flat.pfm "$mesh.pfm"; then fail "$mesh does not render exactly as the OBJ: $(compare obj-flat.pfm "$mesh.pfm")"
  else echo "$mesh renders exactly as the OBJ"; fi
done
# Elsewhere within Monte Carlo noise at the same seed: positions quantized to 16 bits under a node
# (KHR_mesh_quantization, alone, with meshopt's triangle codec, which may rotate corners, and with
# Draco storing the shorts, which its accessor's componentType 5122 tells how to read; refused
# before) and Draco's Edgebreaker (14-bit positions, its own vertex and triangle order), also with
# its POSITION accessor counting 30 points fewer than decode (read as decoded, noted; refused before). With cosine sampling a
# pixel is rho times the share of its N samples that escape, so its noise is binomial; two renders
# with different seeds differ by the noise of both, sqrt(2) times that of one (in mean absolute
# difference too, for errors alike in distribution). Bound: the same-seed difference from the OBJ
# at most the noise of one render, mean |OBJ(seed 3) - OBJ(seed 4)| / sqrt(2). Measured at 96x72,
# 64 spp: noise 0.0114; Draco 0.00001 (a few pixels), the quantized forms 0 so far (a 16-bit step
# moves no hit enough to change a sample).
noisy() { "$bin" --headless -q --size 96x72 --spp 64 --adaptive off --sampler random "$@"; }
noisy --seed 3 --crease-angle 0 "$obj" -o noise3.pfm && noisy --seed 4 --crease-angle 0 "$obj" -o noise4.pfm ||
  fail "the OBJ did not render"
for mesh in quantized.gltf meshopt-quantized.glb draco.glb draco-quantized.glb draco-fewer.glb; do
  if ! noisy --seed 3 "$mesh" -o "$mesh-noisy.pfm"; then fail "$mesh did not render"; continue; fi
  python3 - noise3.pfm noise4.pfm "$mesh-noisy.pfm" "$mesh" <<'PY' || fail "$mesh differs from the OBJ by more than Monte Carlo noise"
import math, struct, sys
def read(path):
    data = open(path, 'rb').read()
    head = data.split(b'\n', 3)
    w, h = map(int, head[1].split())
    return struct.unpack('<%df' % (3 * w * h), head[3])
a, b, c = (read(p) for p in sys.argv[1:4])
mad = lambda x, y: sum(abs(p - q) for p, q in zip(x, y)) / len(x)
noise, got = mad(a, b) / math.sqrt(2), mad(a, c)
print('%s: mean difference from the OBJ %.5f, noise of one render %.5f' % (sys.argv[4], got, noise))
sys.exit(0 if got <= noise else 1)
PY
done

# The normals a file lacks, on shapes flat or smooth by construction (tests/tools/shapes.py). A cube is
# flat: the OBJ (its 8 corners shared) and the binary STL render byte for byte as --shading flat;
# so does the glTF cube without NORMAL, welded (indexed, as gltfpack and Draco write it: it rendered
# rounded with a dark base, mean difference 0.037) and unwelded (every triangle its own vertices).
shapes=$root/tests/tools/shapes.py
python3 "$shapes" cube cube.obj && python3 "$shapes" cube cube-unwelded.obj --unwelded &&
  python3 "$convert" cube.obj cube.stl && python3 "$convert" cube.obj cube.glb &&
  python3 "$convert" cube-unwelded.obj cube-unwelded.gltf || fail "no cube"
render cube.obj --shading flat -o cube-flat.pfm || fail "the cube did not render"
for mesh in cube.obj cube.stl cube.glb cube-unwelded.gltf; do
  if ! render "$mesh" -o "$mesh.pfm"; then fail "$mesh did not render"
  elif ! cmp -s cube-flat.pfm "$mesh.pfm"; then fail "$mesh is not flat: $(compare cube-flat.pfm "$mesh.pfm")"
  else echo "$mesh renders exactly as --shading flat"; fi
done
# A coarse sphere (16 x 8 facets, 22.5 degrees apart) stays smooth, and a CAD-like part keeps its
# 45- and 90-degree edges sharp while its rounded edges (22.5 degrees) and boss (15) stay smooth:
# their normals, as the normals view shows them, lie as near the exact ones (the --normals files)
# as the crease angle allows, and far from flat or from smoothing everywhere. Measured at 96x72
# (normals view, mean |difference| over the pixels): the sphere 0.0003 from its exact normals
# against 0.0044 flat; the part 0.0004 against 0.0129 smoothed everywhere. Bound: a third of the
# second.
python3 "$shapes" sphere sphere.obj && python3 "$shapes" sphere sphere-exact.obj --normals &&
  python3 "$shapes" part part.obj && python3 "$shapes" part part-exact.obj --normals || fail "no sphere or part"
view() { render --view normals "$@"; }
view sphere-exact.obj -o sphere-exact.pfm && view sphere.obj -o sphere.pfm && view sphere.obj --crease-angle 0 \
  -o sphere-flat.pfm && view part-exact.obj -o part-exact.pfm && view part.obj -o part.pfm &&
  view part.obj --crease-angle 180 -o part-round.pfm || fail "the sphere or the part did not render"
python3 - <<'PY' || fail "the sphere or the part: normals not as their shapes are"
import struct
def read(path):
    data = open(path, 'rb').read()
    head = data.split(b'\n', 3)
    w, h = map(int, head[1].split())
    return struct.unpack('<%df' % (3 * w * h), head[3])
mad = lambda x, y: sum(abs(p - q) for p, q in zip(read(x), read(y))) / len(read(x))
ok = True
for shape, wrong in (('sphere', 'sphere-flat'), ('part', 'part-round')):
    near, far = mad(shape + '-exact.pfm', shape + '.pfm'), mad(shape + '-exact.pfm', wrong + '.pfm')
    print('%s: normals %.4f from the exact ones, %s %.4f' % (shape, near, wrong, far))
    ok = ok and near < far / 3
raise SystemExit(0 if ok else 1)
PY

# What aoview says of them: the joining triangles of the strip skipped as zero-area (one line with
# the points and lines it also skipped), a required material extension in one line, and without
# --ground the mesh alone (the OBJ's 3674 triangles, not 3676).
python3 - <<'PY'
import json
doc = json.load(open('strip.gltf'))
doc['meshes'][0]['primitives'].append({'attributes': {'POSITION': 0}, 'mode': 1})
doc['meshes'][0]['primitives'].append({'attributes': {'POSITION': 0}, 'mode': 0})
doc['extensionsUsed'] = doc['extensionsRequired'] = ['KHR_materials_emissive_strength', 'KHR_texture_transform']
json.dump(doc, open('said.gltf', 'w'))
strip = doc['accessors'][doc['meshes'][0]['primitives'][0]['indices']]['count']
open('joins.txt', 'w').write('%d' % (strip - 2 - 3674))   # the strip's triangles less the OBJ's
PY
"$bin" --headless --size 32x24 --spp 1 -o said.pfm said.gltf 2>said.txt || fail "said.gltf did not render"
for line in "aoview: skipped $(cat joins.txt) degenerate triangles, 1 point primitive and 1 line primitive" \
            "aoview: said.gltf: materials, textures and lights are ignored (it requires KHR_materials_emissive_strength, KHR_texture_transform)" \
            "aoview: said.gltf: 3676 triangles, 0 spheres"; do
  grep -q "^$line" said.txt || fail "said.gltf: no line '$line' in: $(cat said.txt)"
done
"$bin" --headless --size 32x24 --spp 1 -o fewer.pfm draco-fewer.glb 2>fewer.txt || fail "draco-fewer.glb did not render"
line="aoview: draco-fewer.glb: mesh 0 primitive 0 (KHR_draco_mesh_compression): accessor 0 counts 1809 points where its data decode to 1839: read as decoded"
grep -qxF "$line" fewer.txt || fail "draco-fewer.glb: no line '$line' in: $(cat fewer.txt)"
"$bin" --headless --size 32x24 --spp 1 --ground off -o bare.pfm "$obj" 2>bare.txt || fail "--ground off did not render"
grep -q "bunny.obj: 3674 triangles" bare.txt || fail "--ground off: $(cat bare.txt)"

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
finish
