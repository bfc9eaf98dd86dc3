#!/bin/bash
# Benchmark: time to the first result. hyperfine times, for each aoview binary given (the built one
# and, say, an older build to compare), `--version`, a 1x1 headless PFM of sphere-on-plane (start,
# scene, BVH and output with nothing to trace) and the same as PNG (plus OSMesa's load, context and
# shaders), and bunny at 256x256 with 16 spp as PFM and as PNG; and the floor: BARE, a program
# linked to Embree alone that creates a device. Rounds of all commands in turn (the machine may be
# shared), then each command's median wall time over all runs, its quartiles, its mean CPU time and
# its excess over BARE's median.
# Prints figures; asserts nothing. Exits 77 without hyperfine or python3.
# Run: meson test -C build --benchmark startup -v
#  or: bash tests/bench/bench_startup.sh build/tests/bench_embree_start build/aoview OTHER/aoview
set -u
bare=${1:?usage: bench_startup.sh BARE AOVIEW [AOVIEW...]}
shift
[ $# -gt 0 ] || { echo "usage: bench_startup.sh BARE AOVIEW [AOVIEW...]"; exit 2; }
for tool in hyperfine python3; do
    command -v $tool >/dev/null || { echo "SKIP: $tool is not installed"; exit 77; }
done
scenes=$(cd "$(dirname "$0")/../../assets/scenes" && pwd)
rounds=${AO_ROUNDS:-5}
runs=${AO_RUNS:-10}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

commands=("$bare")
for aoview in "$@"; do
    commands+=("$aoview --version"
               "$aoview --headless -q --size 1x1 --spp 1 -o $work/tiny.pfm $scenes/sphere-on-plane.scene"
               "$aoview --headless -q --size 1x1 --spp 1 -o $work/tiny.png $scenes/sphere-on-plane.scene"
               "$aoview --headless -q --size 256x256 --spp 16 -o $work/bunny.pfm $scenes/bunny.scene"
               "$aoview --headless -q --size 256x256 --spp 16 -o $work/bunny.png $scenes/bunny.scene")
done

echo "$(date -u '+%Y-%m-%d %H:%M UTC'), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg);" \
     "$rounds rounds of $runs runs per command"
for round in $(seq "$rounds"); do
    hyperfine -N --warmup 2 --runs "$runs" --export-json "$work/$round.json" "${commands[@]}" \
        >/dev/null 2>"$work/hyperfine.txt" || { cat "$work/hyperfine.txt"; exit 1; }
done
python3 - "$work" "$rounds" "$scenes" <<'PY'
import json, statistics, sys
work, rounds, scenes = sys.argv[1], int(sys.argv[2]), sys.argv[3]
wall, cpu = {}, {}
for r in range(1, rounds + 1):
    for result in json.load(open(f"{work}/{r}.json"))["results"]:
        wall.setdefault(result["command"], []).extend(result["times"])
        cpu.setdefault(result["command"], []).append(result["user"] + result["system"])
floor = None
print("| median ms | quartiles ms | CPU ms | over bare ms | command |")
print("|---|---|---|---|---|")
for command, times in wall.items():
    times = sorted(t * 1e3 for t in times)
    median = statistics.median(times)
    floor = median if floor is None else floor
    quartiles = statistics.quantiles(times, n=4)
    print(f"| {median:.1f} | {quartiles[0]:.1f}–{quartiles[2]:.1f} | {statistics.mean(cpu[command]) * 1e3:.1f} "
          f"| {median - floor:+.1f} | `{command.replace(work, '$TMP').replace(scenes, 'assets/scenes')}` |")
PY
