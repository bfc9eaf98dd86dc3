#!/bin/bash
# What aoview loads: `--version` and a headless PFM render initialize no OpenGL library (libOSMesa,
# the LLVM it brings, libglapi, libGL, libEGL, libGLX); a headless PNG loads libOSMesa and LLVM
# when it reads back, which also shows that the log below sees libraries opened at run time.
# The evidence is the dynamic loader's own log (LD_DEBUG=libs, written to files by
# LD_DEBUG_OUTPUT), which has one "calling init: PATH" line for every library it initializes,
# linked or opened later. Needs AO_BINARY and AO_SOURCE_ROOT.
. "$(dirname "$0")/lib.sh"
scene=$root/assets/scenes/spheres.scene
gl='/lib(OSMesa|LLVM|glapi|GL|EGL|GLX)[-.][^/]*$'

fail() {
    echo "FAIL: $*"
    exit 1
}

# Runs aoview with the arguments under the loader's log; the names of the libraries it
# initialized, one a line, in $libraries.
libraries() {
    rm -f ld.*
    LD_DEBUG=libs LD_DEBUG_OUTPUT=$work/ld "$AO_BINARY" "$@" >/dev/null 2>err.txt ||
        fail "aoview $* failed: $(cat err.txt)"
    libraries=$(cat ld.* 2>/dev/null | sed -n 's/.*calling init: //p')
    [ -n "$libraries" ] || fail "no loader log from aoview $* (LD_DEBUG ignored?)"
}

# Checks that aoview with the arguments initializes no OpenGL library.
no_gl() {
    libraries "$@"
    local found
    found=$(grep -E "$gl" <<<"$libraries")
    [ -z "$found" ] || fail "aoview $* loads" $found
    echo "ok: aoview $* loads $(wc -l <<<"$libraries") libraries, none of OpenGL"
}

no_gl --version
no_gl --headless -q --size 40x30 --spp 4 -o out.pfm "$scene"
[ -s out.pfm ] || fail "out.pfm missing"

libraries --headless -q --size 40x30 --spp 4 -o out.png "$scene"
[ -s out.png ] || fail "out.png missing"
for name in libOSMesa libLLVM; do
    grep -q "/$name[-.]" <<<"$libraries" || fail "the PNG run did not load $name: the log misses dlopen"
done
echo "ok: a PNG loads $(grep -E "$gl" <<<"$libraries" | xargs -n1 basename | tr '\n' ' ')"
echo PASS
