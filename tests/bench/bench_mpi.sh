#!/usr/bin/env bash
# Whole runs of the bunny (defaults; 640x480 and 256 spp unless SIZE or SPP is set) as one aoview
# process and as aoview-mpi under mpirun on this machine, interleaved REPS times (ONLY="0 3": those
# configurations alone, the first always among them); prints the median wall seconds
# and CPU seconds (user + system, the ranks' and mpirun's) of each configuration and its throughput
# relative to one 2-thread aoview by both (the images are the same, so the rays are too): on a
# machine busy with other work, wall time measures the share of the cores a configuration gets,
# CPU time what it costs. Run: bash tests/bench/bench_mpi.sh BUILD_DIR [REPS] (docs/mpi.md).
set -eu
build=${1:?build dir}
reps=${2:-5}
size=${SIZE:-640x480}
spp=${SPP:-256}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl_tcp_if_include=lo OMPI_MCA_oob_tcp_if_include=lo
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The last: OpenMPI told to use its ob1 messaging at once (--mca pml ob1), not to probe first for
# the fabrics it would prefer (PSM, PSM2, OFI), which no machine without them needs (docs/mpi.md).
configs=("aoview --threads 2" "aoview --threads 1" "mpirun -np 1 --threads 2" "mpirun -np 2 --threads 1"
         "mpirun -np 3 --threads 1" "mpirun -np 2 --threads 2" "mpirun --mca pml ob1 -np 2 --threads 1")
run() {
  local words=($1) timing=(/usr/bin/time -f "%e %U %S" -o "$work/one")
  if [ "${words[0]}" = aoview ]; then
    "${timing[@]}" "$build/aoview" --headless -q --size "$size" --spp "$spp" "${words[1]}" "${words[2]}" -o "$work/x.pfm"
  else
    local n=${#words[@]}
    "${timing[@]}" "${words[0]}" --oversubscribe "${words[@]:1:n-3}" "$build/aoview-mpi" --headless -q --size "$size" \
      --spp "$spp" "${words[n-2]}" "${words[n-1]}" -o "$work/x.pfm"
  fi
}
for ((k = 0; k < reps; k++)); do
  for c in ${ONLY:-${!configs[@]}}; do
    run "${configs[$c]}"
    echo "$c $(cat "$work/one")" >> "$work/times"
  done
done
python3 - "$work/times" "${configs[@]}" <<'PY'
import statistics, sys
wall, cpu = {}, {}
for line in open(sys.argv[1]):
    c, e, u, s = line.split()
    wall.setdefault(int(c), []).append(float(e))
    cpu.setdefault(int(c), []).append(float(u) + float(s))
names = sys.argv[2:]
w0, c0 = statistics.median(wall[0]), statistics.median(cpu[0])
# "by wall, paired": the median over rounds of one 2-thread aoview's wall time over the
# configuration's in the same round, which a machine whose speed drifts between rounds moves less.
print('| configuration | wall s (median) | wall runs | throughput by wall | by wall, paired | CPU s (median) | throughput by CPU |')
print('|---|---|---|---|---|---|---|')
for c, name in enumerate(names):
    if c not in wall:
        continue
    w, u = statistics.median(wall[c]), statistics.median(cpu[c])
    paired = statistics.median(a / b for a, b in zip(wall[0], wall[c]))
    print('| `%s` | %.2f | %s | %.0f %% | %.0f %% | %.2f | %.0f %% |' % (name, w, ' '.join('%.2f' % t for t in wall[c]),
                                                              100.0 * w0 / w, 100.0 * paired, u, 100.0 * c0 / u))
PY
